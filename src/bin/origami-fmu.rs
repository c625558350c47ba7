//! The `origami-fmu` command line: pattern, check, build, simulate.
fn main() -> std::process::ExitCode {
    origami_fmu::cli::main()
}
