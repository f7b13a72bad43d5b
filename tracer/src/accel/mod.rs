//! The fast paths: each computes what the model computes (the same bits,
//! or the same expectation where it says so), faster, for the scenes and
//! options it supports. Each is one file; none is imported by the model
//! below it, which they reach through the interfaces it defines (the
//! walls' ray queries with lists, `path::MirrorWalls`, the light
//! interface, `light::Strata`).
//!
//! - `culling`: per block of pixels and arc of directions, the walls the
//!   floor's rays can meet, and per light the walls its shadow rays can
//!   cross.
//! - `coherence`: per pixel and light, whether a shadow edge crosses the
//!   pixel; where none does, the floor memo's points share one shadow ray.
//! - `strata`: the floor memo's points light by light, line lights'
//!   angle samples in lanes.
//! - `shortcut`: a one-bounce path read straight from the wall memo.
//! - `dark`: cells of the light table that a wall hides from a light.
//! - `mirror`: per piece of mirror and arc of directions, the walls rays
//!   off it can meet.

pub(crate) mod coherence;
pub(crate) mod culling;
pub(crate) mod dark;
pub(crate) mod mirror;
pub(crate) mod shortcut;
pub(crate) mod strata;
