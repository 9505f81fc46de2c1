//! `sss`: the command-line tool (thin glue over [`sss_render::cli`]).

fn main() -> std::process::ExitCode {
    sss_render::cli::main(std::env::args_os())
}
