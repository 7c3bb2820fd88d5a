//! The `chisel` binary: see `chisel --help`.

fn main() -> std::process::ExitCode {
    chisel::cli::main()
}
