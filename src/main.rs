use clap::Parser;

fn main() -> std::process::ExitCode {
    ngcflat::run(ngcflat::config::Cli::parse())
}
