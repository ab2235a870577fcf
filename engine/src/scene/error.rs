//! The error a scene file gets.

use std::fmt;
use std::path::PathBuf;

/// An error in a scene file, naming the file, the field and what is allowed.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneError {
    pub file: PathBuf,
    /// Dotted path of the field (`law.kappa`, `protocol[1].pressure`), empty for syntax errors.
    pub field: String,
    pub message: String,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        if self.field.is_empty() {
            write!(f, "scene {}: {}", self.file.display(), self.message)
        } else {
            write!(
                f,
                "scene {}: field `{}`: {}",
                self.file.display(),
                self.field,
                self.message
            )
        }
    }
}

impl std::error::Error for SceneError {}
