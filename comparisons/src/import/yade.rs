//! Reader of the final state written by our yade decks.

use super::{ImportError, Meta, Raw};
use std::path::Path;

/// Reads the final files of a yade run in `dir`.
pub fn read_dir(dir: &Path, _meta: &Meta) -> Result<Raw, ImportError> {
    Err(ImportError::new(dir, "yade reader not written yet"))
}
