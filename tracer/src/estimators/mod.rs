//! The closed forms: estimators of whole classes of light paths that
//! compute their light rather than sample it. Each module says which
//! classes it counts; `ledger.rs` says which estimator counts each class,
//! and the plan decides (`Plan::ledger`) where each runs.
//!
//! - `exact.rs`: a line or circle light seen directly from a receiver
//!   point, and through one flat mirror (`Ledger::mirror_lights`);
//! - `refracted.rs`: a line or circle light seen from inside a smooth
//!   glass body through one of its edges (`Ledger::glass_lights`);
//! - `square.rs`: a point, spot or sun averaged over a pixel's square of
//!   the floor.
//!
//! What the lights themselves answer (a sample of their light at a point,
//! their power, a photon) is `lights/`; these modules ask it and never
//! sample a light themselves.

pub(crate) mod choice;
mod contribution;
pub(crate) mod exact;
pub(crate) mod refracted;
pub(crate) mod square;

pub(crate) use contribution::{
    Receiver, Visibility, light_contribution, transmittance, weighed_contribution,
};
pub(crate) use exact::{MAX_MIRROR_PAIRS, is_exact, through_mirrors, through_mirrors_of};
pub(crate) use refracted::{MAX_GLASS_PAIRS, glass_pairs, through_glass, through_glass_of};
