//! `egogen`: tools around the pipeline (body models, motion, policy, scenes, exports,
//! previews). Its command line is `egogen::commands::egogen`.

fn main() -> std::process::ExitCode {
    egogen::commands::egogen::main()
}
