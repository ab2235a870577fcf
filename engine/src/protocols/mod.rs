//! Hard-grain preparation protocols: event-driven hard-sphere / hard-disk dynamics with
//! elastic collisions and Lubachevsky–Stillinger growth ([`event_driven`]; AR07 §III, §III.A,
//! §IV.B), and crystal lattices for the initial states ([`lattice`]; AR07 §III).

pub mod event_driven;
pub mod lattice;
