//! The `shikki` command; all logic lives in `shikki::cli`.
fn main() -> std::process::ExitCode {
    shikki::cli::main()
}
