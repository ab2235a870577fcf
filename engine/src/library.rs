//! Scenes embedded in the binary (the files of `reference-inputs/scenes/`).

macro_rules! scenes {
    ($($name:literal),* $(,)?) => {
        &[$(($name, include_str!(concat!("../../reference-inputs/scenes/", $name, ".toml")))),*]
    };
}

/// (name, TOML text) of every embedded scene; `default` is what a bare `grainbench run` runs.
pub const SCENES: &[(&str, &str)] = scenes!(
    "default",
    "xcode-smoke",
    "xcode-cohesive-smoke",
    "xcode-cohesive-classes-smoke",
    "xcode-cohesive-rr-smoke",
    "xcode-sjkr-smoke",
    "xcode-dmt-smoke",
    "impact-normal",
    "impact-oblique",
    "impact-chain",
    "impact-spin",
    "ar07-A-n1372",
    "ar07-D-10kPa-n1372",
    "ar07-D-10kPa-n1372-quench",
    "ar07-D-10kPa-n1372-relax",
    "ar07-A",
    "ar07-A-ci",
    "ar07-Aprime",
    "ar07-Aprime-ci",
    "ar07-B",
    "ar07-B-ci",
    "ar07-C",
    "ar07-C-ci",
    "ar07-D",
    "ar07-D-10kPa",
    "ar07-D-QS",
    "ar07-D-QS-ci",
    "ar07-D-ci",
    "ar07-Z",
    "ar07-Z-ci",
    "ar07-frictionless-small",
    "grc07-cohesionless-phi013-mu015",
    "grc07-cohesionless-phi013-mu015-rr",
    "grc07-cohesionless-phi013-mu05",
    "grc07-cohesionless-phi013-mu05-rr",
    "grc07-cohesionless-phi036-mu015",
    "grc07-cohesionless-phi036-mu015-rr",
    "grc07-cohesionless-phi036-mu05",
    "grc07-cohesionless-phi036-mu05-ci",
    "grc07-cohesionless-phi036-mu05-rr",
    "grc07-cohesionless-phi052-mu015",
    "grc07-cohesionless-phi052-mu015-rr",
    "grc07-cohesionless-phi052-mu05",
    "grc07-cohesionless-phi052-mu05-rr",
    "grc07-cohesive-small",
    "grc07-type1-phi013-mu015",
    "grc07-type1-phi013-mu015-rr",
    "grc07-type1-phi013-mu05",
    "grc07-type1-phi013-mu05-rr",
    "grc07-type1-phi036-mu015",
    "grc07-type1-phi036-mu015-rr",
    "grc07-type1-phi036-mu05",
    "grc07-type1-phi036-mu05-rr",
    "grc07-type1-phi036-mu05-rr-ci",
    "grc07-type1-phi052-mu015",
    "grc07-type1-phi052-mu015-rr",
    "grc07-type1-phi052-mu05",
    "grc07-type1-phi052-mu05-rr",
    "grc07-type1-phi052-mu05-rr-classes",
    "grc07-type2-phi026",
    "grc07-type2-phi026-rr",
    "grc07-type2-phi026-stepped",
    "grc07-type2-phi026-rr-stepped",
    "grc07-type2-phi026-p0",
    "grc07-type2-phi026-rr-p0",
    "grc07-type2-phi036",
    "grc07-type2-phi036-ci",
    "grc07-type2-phi036-p0",
    "grc07-type2-phi036-rr",
    "grc07-type2-phi036-rr-ci",
    "grc07-type2-phi036-rr-p0",
    "grc07-type2-phi036-rr-p0-v0-0p095",
    "grc07-type2-phi036-rr-p0-v0-0p95",
    "grc07-type2-phi036-rr-p0-v0-95",
    "grc07-type2-phi036-rr-p0-v0-9p5",
    "grc08-cycle",
    "grc08-cycle-rr",
    "grc08-cycle-rr-ci",
    "grc08-cycle-rr05",
    "grc08-cycle-type1",
    "grc08-cycle-type1-rr",
);

/// The embedded scene called `name`.
pub fn scene_text(name: &str) -> Option<&'static str> {
    SCENES.iter().find(|(n, _)| *n == name).map(|(_, t)| *t)
}

/// The embedded scene called `name`, read (errors name the file `<embedded:NAME>`).
pub fn scene(name: &str) -> Option<Result<crate::Scene, crate::scene::SceneError>> {
    let text = scene_text(name)?;
    Some(crate::Scene::from_toml(
        text,
        std::path::Path::new(&format!("<embedded:{name}>")),
    ))
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
        // Every scene file is embedded.
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../reference-inputs/scenes");
        for f in std::fs::read_dir(dir).unwrap() {
            let name = f.unwrap().file_name().into_string().unwrap();
            let stem = name.trim_end_matches(".toml");
            assert!(scene_text(stem).is_some(), "{name} is not embedded");
        }
    }
}
