//! `mpirun` command lines for tests and tools that start MPI jobs: one
//! place that knows which launcher options a container or a CI machine
//! needs. Builds a [`Command`] only, so it needs no MPI library and no
//! `mpi` feature.
//!
//! For Open MPI (recognised by `mpirun --version`) the command gets
//! `--oversubscribe` (more ranks than cores, as tests on small machines
//! ask for), `--allow-run-as-root` (containers often run as root) and the
//! environment `OMPI_MCA_btl_vader_single_copy_mechanism=none` (containers
//! often forbid the cross-memory-attach copy). Other MPIs (MPICH, Intel
//! MPI) get `mpirun -n N` alone.
//!
//! ```no_run
//! // `mpirun -n 2 ./my-mpi-program --flag`, with the options the installed
//! // MPI needs; an error naming `mpirun` when there is none.
//! let status = sph_comm::launch::mpirun(2)?
//!     .arg("./my-mpi-program")
//!     .arg("--flag")
//!     .status()?;
//! assert!(status.success());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! Which options a launcher gets follows from its `--version` text alone:
//!
//! ```
//! use sph_comm::launch::Launcher;
//!
//! let open_mpi = Launcher::from_version("mpirun (Open MPI) 4.1.4");
//! assert!(open_mpi.is_open_mpi());
//! assert_eq!(open_mpi.words(), ["mpirun", "--oversubscribe", "--allow-run-as-root"]);
//! let cmd = open_mpi.command(4);
//! let args: Vec<_> = cmd.get_args().collect();
//! assert_eq!(args, ["-n", "4", "--oversubscribe", "--allow-run-as-root"]);
//!
//! let mpich = Launcher::from_version("HYDRA build details:\n    Version: 4.0");
//! assert_eq!(mpich.words(), ["mpirun"]);
//! assert!(mpich.env().is_empty());
//! ```

use std::process::Command;

/// The launcher program.
pub const PROGRAM: &str = "mpirun";

/// Options Open MPI needs to run tests on small machines and in
/// containers.
const OPEN_MPI_OPTIONS: [&str; 2] = ["--oversubscribe", "--allow-run-as-root"];

/// Environment Open MPI needs in containers.
const OPEN_MPI_ENV: [(&str, &str); 1] = [("OMPI_MCA_btl_vader_single_copy_mechanism", "none")];

/// Why no launcher command could be built.
#[derive(Debug, thiserror::Error)]
pub enum LaunchError {
    /// `mpirun --version` could not be run.
    #[error(
        "cannot run `{PROGRAM} --version` ({source}): no MPI launcher on PATH; install one \
         (e.g. Debian's openmpi-bin) to run the MPI tests"
    )]
    NotFound {
        /// The cause.
        source: std::io::Error,
    },
}

/// The installed MPI launcher and the options it needs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Launcher {
    open_mpi: bool,
}

impl Launcher {
    /// Asks `mpirun --version` which MPI is installed.
    ///
    /// # Errors
    /// [`LaunchError::NotFound`] when `mpirun` cannot be run.
    pub fn detect() -> Result<Self, LaunchError> {
        let out = Command::new(PROGRAM)
            .arg("--version")
            .output()
            .map_err(|source| LaunchError::NotFound { source })?;
        // Open MPI prints its name on stdout, some versions on stderr.
        let text = String::from_utf8_lossy(&out.stdout) + String::from_utf8_lossy(&out.stderr);
        Ok(Self::from_version(&text))
    }

    /// The launcher whose `mpirun --version` printed `text`.
    pub fn from_version(text: &str) -> Self {
        Launcher {
            open_mpi: text.contains("Open MPI") || text.contains("OpenRTE"),
        }
    }

    /// Whether it is Open MPI.
    pub fn is_open_mpi(&self) -> bool {
        self.open_mpi
    }

    /// The program and its options, without the rank count: the words of
    /// a launcher prefix such as `sphexa bench --mpirun "..."` takes.
    pub fn words(&self) -> Vec<&'static str> {
        let mut w = vec![PROGRAM];
        if self.open_mpi {
            w.extend(OPEN_MPI_OPTIONS);
        }
        w
    }

    /// The environment the launcher's processes need (name, value).
    pub fn env(&self) -> &'static [(&'static str, &'static str)] {
        if self.open_mpi {
            &OPEN_MPI_ENV
        } else {
            &[]
        }
    }

    /// `mpirun -n RANKS` with the options and environment it needs; the
    /// caller adds the program and its arguments.
    pub fn command(&self, ranks: usize) -> Command {
        let words = self.words();
        let mut c = Command::new(words[0]);
        c.arg("-n").arg(ranks.to_string()).args(&words[1..]);
        c.envs(self.env().iter().copied());
        c
    }
}

/// `mpirun -n RANKS` for the installed MPI ([`Launcher::detect`], then
/// [`Launcher::command`]).
///
/// # Errors
/// [`LaunchError::NotFound`] when `mpirun` cannot be run.
pub fn mpirun(ranks: usize) -> Result<Command, LaunchError> {
    Ok(Launcher::detect()?.command(ranks))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn open_mpi_gets_its_options_and_environment_and_others_none() {
        for text in ["mpirun (Open MPI) 4.1.4\n", "mpirun (OpenRTE) 2.1.1"] {
            let l = Launcher::from_version(text);
            assert!(l.is_open_mpi(), "{text}");
            let c = l.command(3);
            assert_eq!(c.get_program(), PROGRAM);
            let args: Vec<_> = c.get_args().collect();
            assert_eq!(args, ["-n", "3", "--oversubscribe", "--allow-run-as-root"]);
            let env: Vec<_> = c.get_envs().collect();
            assert_eq!(
                env,
                [(
                    std::ffi::OsStr::new("OMPI_MCA_btl_vader_single_copy_mechanism"),
                    Some(std::ffi::OsStr::new("none"))
                )]
            );
        }
        let l = Launcher::from_version("HYDRA build details:\n    Version: 4.1.2");
        assert!(!l.is_open_mpi());
        let c = l.command(2);
        assert_eq!(c.get_args().collect::<Vec<_>>(), ["-n", "2"]);
        assert_eq!(c.get_envs().count(), 0);
    }

    #[test]
    fn a_missing_launcher_is_named() {
        let e = LaunchError::NotFound {
            source: std::io::Error::from(std::io::ErrorKind::NotFound),
        };
        let text = e.to_string();
        assert!(
            text.contains("mpirun --version") && text.contains("openmpi-bin"),
            "{text}"
        );
    }
}
