//! liggghts deck generator.

use super::{Code, Deck, Start};

/// The liggghts deck of `start`.
pub fn deck(start: &Start, deviations: &[String]) -> Deck {
    let _ = (start, deviations);
    Deck {
        code: Code::Yade,
        files: Vec::new(),
        deviations: Vec::new(),
        args: Vec::new(),
    }
}
