//! Scenes embedded in the binary (the files of `reference-inputs/scenes/`).

macro_rules! scenes {
    ($($name:literal),* $(,)?) => {
        &[$(($name, include_str!(concat!("../../reference-inputs/scenes/", $name, ".toml")))),*]
    };
}

/// (name, TOML text) of every embedded scene; `default` is what a bare `grainbench run` runs.
pub const SCENES: &[(&str, &str)] = scenes!(
    "default",
    "ar07-frictionless-small",
    "grc07-cohesionless-small",
    "grc07-cohesive-small",
);

/// The embedded scene called `name`.
pub fn scene_text(name: &str) -> Option<&'static str> {
    SCENES.iter().find(|(n, _)| *n == name).map(|(_, t)| *t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn every_embedded_scene_is_valid_and_named_after_its_file() {
        for (name, text) in SCENES {
            let scene = crate::Scene::from_toml(text, Path::new(name)).unwrap();
            assert_eq!(&scene.name, name);
        }
    }
}
