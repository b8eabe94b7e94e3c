//! `sphexa`: run the SPH-EXA test cases from the command line (the
//! command line itself is [`sph_apps::cli`]).

fn main() -> std::process::ExitCode {
    sph_apps::cli::main()
}
