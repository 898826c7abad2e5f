"""rcsc: a compiler and checker for NIST RCS (Real-time Control System) designs.

The folders follow the pipeline, one stage each:

    front/      source text -> syntax trees (text_to_ast), scenarios
    semantics/  syntax trees -> the checked model (ast_to_model), types, numbers
    checks/     the model -> findings (check_model), one check family per module
    sim/        the model -> traces: the reference simulator and scenario runs
    outputs/    the model -> generated code (backend), pictures, documentation
    editor/     the language server, the formatter, shell completion

The modules at the top are what every stage shares: the diagnostics and their
codes and renderings, the configuration, the driver that chains the stages and
the command line.

Every stage collects `Diagnostic` objects into a shared `Diagnostics` bag instead
of raising, so one run reports every finding.
"""

__version__ = "0.1.0"
