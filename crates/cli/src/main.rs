//! `sss`: the command-line tool (thin glue over [`sss_cli::main`]).

fn main() -> std::process::ExitCode {
    sss_cli::main(std::env::args_os())
}
