//! Cross-code comparison: the same scene run by LAMMPS, LIGGGHTS and YADE — the
//! stress-controlled periodic cell (AR07 §II.B, GRC07 §II.A), the equilibrium criteria (AR07
//! §III, GRC07 §II.D) and the assembling procedures (AR07 §III–§IV, GRC07 §III), as far as
//! each code can express them (`docs/external-codes.md`).
//!
//! * [`code`]: the [`Code`] enum (one per DEM code) and executable lookup.
//! * [`adapter`]: adapter files, for any code reading the neutral exchange format.
//! * [`decks`]: input decks for each external code, with the capability matrix.
//! * [`import`]: readers of each code's final dumps into our snapshot format, and the
//!   `deck.json` metadata ([`import::Meta`]) the decks write beside themselves.
//! * [`crosscode`]: the table of every metric of every code against the paper, the golden
//!   values and our engine.
//! * [`seeds`]: those tables over several seeds, each code's mean ± s.d.
//!
//! Imports run one way: `code` ← `import` ← `decks`; `crosscode` takes only [`Code`].

pub mod adapter;
pub mod code;
pub mod crosscode;
pub mod decks;
pub mod import;
pub mod seeds;

pub use code::{which, Code};
