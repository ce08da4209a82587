fn main() -> std::process::ExitCode {
    ngcflat::cli::main()
}
