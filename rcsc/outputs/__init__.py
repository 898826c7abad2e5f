"""Everything rcsc writes: generated code, pictures and documentation.

The backend interface and its naming core, `rcsc graph`, `rcsc doc`, and the
safe file writing that every output goes through.
"""
