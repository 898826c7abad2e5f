"""The Rust target: a no_std controller library and one std binary per CPU."""
