//! The `chisel` command line. PLACEHOLDER.
