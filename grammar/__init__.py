"""Grammar of the RCS design language (data package: rcs.lark)."""
