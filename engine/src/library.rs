//! Scenes embedded in the binary (the files of `reference-inputs/scenes/`).

/// (name, TOML text) of every embedded scene; `default` is what a bare `grainbench run` runs.
pub const SCENES: &[(&str, &str)] = &[(
    "default",
    include_str!("../../reference-inputs/scenes/default.toml"),
)];

/// The embedded scene called `name`.
pub fn scene_text(name: &str) -> Option<&'static str> {
    SCENES.iter().find(|(n, _)| *n == name).map(|(_, t)| *t)
}
