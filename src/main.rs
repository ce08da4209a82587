fn main() -> std::process::ExitCode {
    ngcflat::run(ngcflat::config::Cli::from_env())
}
