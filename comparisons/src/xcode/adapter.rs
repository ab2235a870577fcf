//! Adapter files: any DEM code in the harness. A TOML file says how to run the
//! code on an exchange directory (`docs/exchange-format.md`), how to print its version and
//! which features of the capability matrix it supports; `--codes NAME=PATH.toml` then lets
//! `compare`, `bench`, `golden` and `capabilities` use it like the built-in codes.
//!
//! ```toml
//! description = "my DEM code 2.1"
//! run = ["mydem", "--input", "{exchange}/exchange.json", "--output", "{output}"]
//! version = ["mydem", "--version"]
//! supports = ["hertz-normal", "mindlin-tangential", "coulomb", "stress-control",
//!             "equilibrium-criteria", "contact-dump"]
//! [approximate]
//! hertz-damping = "restitution-based damping"
//! ```
//!
//! Placeholders in `run` and `version`: `{exchange}` (the directory holding exchange.json and
//! particles.csv), `{output}` (where the code writes its final state), `{threads}`,
//! `{adapter_dir}` (the adapter file's directory, for scripts shipped beside it).

use super::decks::feature::{Feature, Support};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// A code described by an adapter file.
#[derive(Debug)]
pub struct Adapter {
    /// The name given on the command line (`NAME=PATH`), used in tables and directories.
    pub name: &'static str,
    pub path: PathBuf,
    pub description: String,
    pub run: Vec<String>,
    pub version: Option<Vec<String>>,
    supports: BTreeMap<Feature, Support>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    #[serde(default)]
    description: String,
    run: Vec<String>,
    #[serde(default)]
    version: Option<Vec<String>>,
    supports: Vec<String>,
    #[serde(default)]
    approximate: BTreeMap<String, String>,
}

/// An adapter file's error, naming the file and the field.
#[derive(Debug, thiserror::Error)]
#[error("adapter {path}: {field}{message}")]
pub struct AdapterError {
    pub path: PathBuf,
    pub field: String,
    pub message: String,
}

const PLACEHOLDERS: [&str; 4] = ["{exchange}", "{output}", "{threads}", "{adapter_dir}"];

static REGISTRY: Mutex<Vec<&'static Adapter>> = Mutex::new(Vec::new());

impl Adapter {
    /// Reads and checks `path`; `name` is what the command line calls the code.
    pub fn read(name: &str, path: &Path) -> Result<Adapter, AdapterError> {
        let e = |field: &str, message: String| AdapterError {
            path: path.to_path_buf(),
            field: if field.is_empty() {
                String::new()
            } else {
                format!("field `{field}`: ")
            },
            message,
        };
        if !valid_name(name) {
            return Err(e("", format!("the code name \"{name}\" must be 1–32 characters among a–z, 0–9, '-' and '_', and not a built-in code's name (rust, lammps, lammps-2025, liggghts, yade, generic)")));
        }
        let text = std::fs::read_to_string(path).map_err(|err| e("", err.to_string()))?;
        let f: File = toml::from_str(&text).map_err(|err| e("", err.to_string()))?;
        if f.run.is_empty() || f.run[0].trim().is_empty() {
            return Err(e("run", "must name the program to run, e.g. run = [\"mydem\", \"{exchange}/exchange.json\", \"{output}\"]".into()));
        }
        if !f.run.iter().any(|a| a.contains("{output}")) {
            return Err(e("run", "must pass `{output}` (where the code writes particles.csv, contacts.csv and status.txt) to the code".into()));
        }
        for (field, args) in [("run", Some(&f.run)), ("version", f.version.as_ref())] {
            for a in args.into_iter().flatten() {
                if let Some(bad) = unknown_placeholder(a) {
                    return Err(e(
                        field,
                        format!(
                            "unknown placeholder `{bad}` in \"{a}\"; known: {}",
                            PLACEHOLDERS.join(", ")
                        ),
                    ));
                }
            }
        }
        if matches!(&f.version, Some(v) if v.is_empty()) {
            return Err(e(
                "version",
                "an empty command; leave the field out if the code cannot print its version".into(),
            ));
        }
        let mut supports = BTreeMap::new();
        for key in &f.supports {
            let feat = feature(key).ok_or_else(|| e("supports", unknown_feature(key)))?;
            supports.insert(feat, Support::Exact);
        }
        for (key, why) in &f.approximate {
            let feat = feature(key).ok_or_else(|| e("approximate", unknown_feature(key)))?;
            supports.insert(feat, Support::Approximate(leak(why.clone())));
        }
        Ok(Adapter {
            name: leak(name.to_string()),
            path: path.to_path_buf(),
            description: f.description,
            run: f.run,
            version: f.version,
            supports,
        })
    }

    /// Reads `path` and registers it under `name` for the rest of the process (so results
    /// naming it can be read back), or returns the one registered earlier under that name.
    pub fn register(name: &str, path: &Path) -> Result<&'static Adapter, AdapterError> {
        // Codes run in their own directories: `{adapter_dir}` must not depend on the cwd.
        let path = &std::path::absolute(path).map_err(|e| AdapterError {
            path: path.to_path_buf(),
            field: String::new(),
            message: e.to_string(),
        })?;
        let mut reg = REGISTRY.lock().expect("adapter registry");
        if let Some(a) = reg.iter().find(|a| a.name == name) {
            if a.path != *path {
                return Err(AdapterError {
                    path: path.to_path_buf(),
                    field: String::new(),
                    message: format!(
                        "the code name `{name}` is already given to {}",
                        a.path.display()
                    ),
                });
            }
            return Ok(a);
        }
        let a: &'static Adapter = Box::leak(Box::new(Adapter::read(name, path)?));
        reg.push(a);
        Ok(a)
    }

    /// The adapter registered under `name`, if any.
    pub fn registered(name: &str) -> Option<&'static Adapter> {
        REGISTRY
            .lock()
            .expect("adapter registry")
            .iter()
            .find(|a| a.name == name)
            .copied()
    }

    /// Its entry in the capability matrix: what the file lists, unsupported otherwise.
    pub fn support(&self, f: Feature) -> Support {
        self.supports
            .get(&f)
            .copied()
            .unwrap_or(Support::Unsupported("not in the adapter's `supports` list"))
    }

    /// `args` with the placeholders filled in.
    pub fn fill(
        &self,
        args: &[String],
        exchange: &Path,
        output: &Path,
        threads: usize,
    ) -> Vec<String> {
        let dir = self.path.parent().unwrap_or(Path::new("."));
        let dir = if dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            dir
        };
        args.iter()
            .map(|a| {
                a.replace("{exchange}", &exchange.display().to_string())
                    .replace("{output}", &output.display().to_string())
                    .replace("{threads}", &threads.to_string())
                    .replace("{adapter_dir}", &dir.display().to_string())
            })
            .collect()
    }
}

impl PartialEq for Adapter {
    fn eq(&self, other: &Self) -> bool {
        self.name == other.name
    }
}
impl Eq for Adapter {}
impl std::hash::Hash for Adapter {
    fn hash<H: std::hash::Hasher>(&self, h: &mut H) {
        self.name.hash(h)
    }
}
impl PartialOrd for Adapter {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Adapter {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.name.cmp(other.name)
    }
}

fn valid_name(name: &str) -> bool {
    (1..=32).contains(&name.len())
        && name
            .chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-' || c == '_')
        && ![
            "rust",
            "lammps",
            "lammps-2025",
            "liggghts",
            "yade",
            "generic",
        ]
        .contains(&name)
}

fn unknown_placeholder(arg: &str) -> Option<&str> {
    let mut rest = arg;
    while let Some(open) = rest.find('{') {
        let tail = &rest[open..];
        let close = tail.find('}').map_or(tail.len(), |c| c + 1);
        let token = &tail[..close];
        if !PLACEHOLDERS.contains(&token) {
            return Some(token);
        }
        rest = &tail[close..];
    }
    None
}

fn feature(key: &str) -> Option<Feature> {
    Feature::ALL.into_iter().find(|f| f.key() == key)
}

fn unknown_feature(key: &str) -> String {
    format!(
        "unknown feature \"{key}\"; the features are the rows of `grainbench capabilities`: {}",
        Feature::ALL.map(|f| f.key()).join(", ")
    )
}

/// Adapter strings live as long as the process (a handful per run).
fn leak(s: String) -> &'static str {
    Box::leak(s.into_boxed_str())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn adapter(text: &str) -> Result<Adapter, AdapterError> {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.toml");
        std::fs::write(&path, text).unwrap();
        Adapter::read("mycode", &path)
    }

    #[test]
    fn reads_supports_and_fills_placeholders() {
        let a = adapter(
            "run = [\"{adapter_dir}/dem\", \"{exchange}/exchange.json\", \"{output}\", \"-j{threads}\"]\nsupports = [\"coulomb\", \"stress-control\"]\n[approximate]\nhertz-damping = \"restitution\"\n",
        )
        .unwrap();
        assert_eq!(a.support(Feature::Coulomb), Support::Exact);
        assert_eq!(
            a.support(Feature::HertzDamping),
            Support::Approximate("restitution")
        );
        assert!(matches!(
            a.support(Feature::Adhesion),
            Support::Unsupported(_)
        ));
        let args = a.fill(&a.run, Path::new("/x/ex"), Path::new("/x/out"), 2);
        assert_eq!(args[1..], ["/x/ex/exchange.json", "/x/out", "-j2"]);
        assert!(args[0].ends_with("/dem") && !args[0].contains('{'));
    }

    #[test]
    fn errors_name_the_field() {
        let e = adapter("run = [\"dem\"]\nsupports = []\n").unwrap_err();
        assert!(e.to_string().contains("field `run`") && e.to_string().contains("{output}"));
        let e = adapter("run = [\"dem\", \"{output}\", \"{input}\"]\nsupports = []\n").unwrap_err();
        assert!(e.to_string().contains("`{input}`"), "{e}");
        let e = adapter("run = [\"dem\", \"{output}\"]\nsupports = [\"hertz\"]\n").unwrap_err();
        assert!(
            e.to_string().contains("field `supports`") && e.to_string().contains("hertz-normal"),
            "{e}"
        );
        let e = adapter("run = [\"dem\", \"{output}\"]\nsupport = []\n").unwrap_err();
        assert!(e.to_string().contains("support"), "{e}");
        let dir = tempfile::tempdir().unwrap();
        let e = Adapter::read("lammps", &dir.path().join("a.toml")).unwrap_err();
        assert!(e.to_string().contains("built-in"), "{e}");
    }
}
