//! `egogen-run`: the pipeline, config in and dataset out, one take or a campaign. Its command
//! line is `egogen::commands::egogen_run`.

fn main() -> std::process::ExitCode {
    egogen::commands::egogen_run::main()
}
