"""The rcsc standard library, written in the RCS language itself (data package)."""
