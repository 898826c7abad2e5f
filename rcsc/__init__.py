"""rcsc: a compiler and checker for NIST RCS (Real-time Control System) designs.

The pipeline is a chain of flat stage modules, each named for what it does:

    source  -> parse (text_to_ast)  -> sema (ast_to_model)  -> checks (check_model)

Every stage collects `Diagnostic` objects into a shared `Diagnostics` bag instead
of raising, so one run reports every finding.
"""

__version__ = "0.1.0"
