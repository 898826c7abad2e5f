"""Editor support: the language server, symbols, the formatter, shell completion."""
