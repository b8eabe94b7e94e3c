//! `sphexa cases`: the registered cases with their defaults, and the
//! scheme presets, each scheme written as the `sphexa run` options that
//! select it.

use crate::cases::{self, Physics, Scheme};
use crate::cli::run::scheme::scheme_flags;
use sph_core::PRESETS;

/// `sphexa cases`: one line per case, then its default scheme as the
/// options that would select it.
pub(crate) fn list_cases() {
    say!(
        "{:<14} {:>6} {:>9}  description",
        "case",
        "side",
        "end time"
    );
    for c in cases::registry() {
        say!(
            "{:<14} {:>6} {:>9}  {}",
            c.name(),
            c.default_side(),
            c.default_end_time(),
            c.description()
        );
        say!(
            "{:<14} scheme: {} --time-steps {}",
            "",
            scheme_options(&c.default_scheme(), c.physics()),
            sph_core::Choice::name(&c.default_time_steps())
        );
    }
    say!("\nscheme presets (sphexa run CASE --scheme NAME):");
    for (name, scheme, what) in PRESETS {
        say!("{name:<14} {what}");
        say!("{:<14} {}", "", scheme_options(&scheme, Physics::IDEAL_GAS));
    }
}

/// A scheme (and the case's softening and Courant factor) written as the
/// `sphexa run` options that select it.
fn scheme_options(s: &Scheme, physics: Physics) -> String {
    let mut text = scheme_flags(s);
    if let Some(soft) = physics.softening {
        text += &format!(" --softening {soft} (self-gravity)");
    }
    if let Some(k) = physics.courant {
        text += &format!(" --courant {k}");
    }
    text
}
