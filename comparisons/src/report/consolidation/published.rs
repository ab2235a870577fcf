//! The published consolidation laws a curve is drawn and judged against (GRC08 T.III).

use super::program::has_program;
use crate::metrics::consolidation::ConsolidationLaw;
use crate::report::paper;
use grainbench_engine::Scene;

/// Whether `reproduce` analyses the scene's levels as a consolidation curve (GRC08 §III: the
/// fit of (9), I(k) along the path): a pressure program reproducing a state whose published
/// values are a consolidation law, or join one ([`paper_curve`]). Other states reached by a
/// program are judged at its end only.
pub fn is_cycle(scene: &Scene, state_key: &str) -> bool {
    has_program(scene) && paper_curve(state_key).is_some()
}

/// The published fit of `state` (GRC08 T.III), if paper-values.toml has its parameters.
pub fn paper_law(state: &str) -> Option<ConsolidationLaw> {
    let v = &paper::paper_values(state)?.values;
    let get = |k: &str| v.get(k).map(|x| x.value);
    Some(ConsolidationLaw {
        p0: get("P0_star")?,
        phi0: get("phi0")?,
        lambda: get("lambda")?,
        alpha: get("alpha")?,
        p1: get("P1_star")?,
    })
}

/// The published law a state's curve is drawn against, with its legend: the state's own fit
/// (GRC08 T.III), or the type 2 law that a type 1 curve joins (`joins`, GRC08 Fig. 6).
pub fn paper_curve(state: &str) -> Option<(ConsolidationLaw, String)> {
    if let Some(law) = paper_law(state) {
        return Some((law, "GRC08 T.III".into()));
    }
    let joined = paper::paper_values(state)?.joins.as_deref()?;
    let law = paper_law(joined)?;
    Some((law, "GRC08 T.III, type 2 (Fig. 6: joined)".into()))
}
