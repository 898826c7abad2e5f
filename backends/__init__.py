"""Code-generation backends (one folder per target); filled in by the backend issues."""
