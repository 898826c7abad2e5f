"""The front end: text to syntax trees.

Source files and spans, the tokenizer and the two parsers (the hand-written
one that runs, the lark grammar that is the reference), the loader that follows
imports, the workspace of several paths, and the scenario reader.
"""
