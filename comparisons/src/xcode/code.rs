//! The DEM codes grainbench compares with, and where their executables are.

use std::fmt;

/// A DEM code grainbench can compare with; written as its [`name`](Code::name).
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum Code {
    Rust,
    Lammps,
    Liggghts,
    Yade,
}

impl Code {
    pub const ALL: [Code; 4] = [Code::Rust, Code::Lammps, Code::Liggghts, Code::Yade];
    pub const EXTERNAL: [Code; 3] = [Code::Lammps, Code::Liggghts, Code::Yade];

    /// Name used on the command line, in directories and in golden files.
    pub fn name(self) -> &'static str {
        match self {
            Code::Rust => "rust",
            Code::Lammps => "lammps",
            Code::Liggghts => "liggghts",
            Code::Yade => "yade",
        }
    }
    pub fn parse(s: &str) -> Option<Code> {
        Code::ALL.into_iter().find(|c| c.name() == s)
    }
    /// Executable looked up on `PATH`.
    pub fn binary(self) -> &'static str {
        match self {
            Code::Rust => "grainbench",
            Code::Lammps => "lmp",
            Code::Liggghts => "liggghts",
            Code::Yade => "yade",
        }
    }
    /// The executable on `PATH`, if installed.
    pub fn find(self) -> Option<std::path::PathBuf> {
        which(self.binary())
    }
    /// How to install it on Debian (`ci/install-externals.sh` does all three).
    pub fn install_hint(self) -> &'static str {
        match self {
            Code::Rust => "cargo install --path .",
            Code::Lammps => "apt-get install -y --no-install-recommends lammps",
            Code::Liggghts => "apt-get install -y --no-install-recommends liggghts",
            Code::Yade => "apt-get install -y --no-install-recommends yade",
        }
    }
}

impl fmt::Display for Code {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl PartialEq<&str> for Code {
    fn eq(&self, other: &&str) -> bool {
        self.name() == *other
    }
}

/// Finds an executable `name` on `PATH`.
pub fn which(name: &str) -> Option<std::path::PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join(name))
        .find(|p| p.is_file())
}
