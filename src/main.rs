fn main() -> std::process::ExitCode {
    stickslip::cli::main()
}
