"""Semantic analysis: syntax trees to the checked design model.

Types, name resolution and type checking, the model (the IR every later stage
reads), and the numeric rules with the evaluator that applies them.
"""
