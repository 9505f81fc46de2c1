//! `sss`: the command-line tool (thin glue over [`sss_cli::main`]). Ctrl-C or SIGTERM deletes
//! the temporary files of writes in flight and exits with status 130
//! ([`sss_cli::install_interrupt_handler`]).

#![forbid(unsafe_code)]

fn main() -> std::process::ExitCode {
    sss_cli::install_interrupt_handler();
    sss_cli::main(std::env::args_os())
}
