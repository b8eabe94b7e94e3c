//! `sphexa stress`: the suite of [`crate::stress`], its table, and whether
//! every scenario passed.

use super::parse::{choice, parse_threads};
use super::start_threads;
use crate::AppError;
use clap::Args;
use sph_core::TimeSteps;
use std::path::PathBuf;

/// The options of `sphexa stress`.
#[derive(Args, Debug)]
pub(crate) struct StressArgs {
    /// The short suite (CI: under 5 minutes on 2 cores).
    #[arg(long)]
    quick: bool,
    /// Worker threads (default: all cores).
    #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = parse_threads)]
    threads: Option<usize>,
    /// Output folder (default out/stress): stress.json and each run's files.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// How particles share time steps in every scenario: `block` (each
    /// particle its own power-of-two step, with the limiter; the default,
    /// as in `sphexa run`) or `global` (one step for all); under `block`
    /// a scenario's step count counts sub-steps. Each scenario's
    /// `particle_updates` figure in stress.json compares the two.
    #[arg(long, value_parser = choice::<TimeSteps>(), default_value = "block")]
    time_steps: TimeSteps,
}

/// `sphexa stress`: the suite, its table, and whether every scenario passed.
pub(crate) fn stress(a: StressArgs) -> Result<bool, AppError> {
    start_threads(a.threads)?;
    let out = a.out.unwrap_or_else(|| PathBuf::from("out/stress"));
    let outcomes = crate::stress::run_suite(&crate::stress::Options {
        quick: a.quick,
        out: out.clone(),
        verbose: true,
        time_steps: a.time_steps,
    })?;
    print!("{}", crate::stress::table(&outcomes));
    let failed = outcomes.iter().filter(|o| !o.pass).count();
    say!(
        "{} of {} passed; {}",
        outcomes.len() - failed,
        outcomes.len(),
        out.join("stress.json").display()
    );
    Ok(failed == 0)
}
