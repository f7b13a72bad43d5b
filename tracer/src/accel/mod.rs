//! The fast paths: each computes what the model computes (the same bits,
//! or the same expectation where it says so), faster, for the scenes and
//! options it supports. Each is one file; none is imported by the model
//! below it, which they reach through the interfaces it defines (the
//! walls' ray queries with lists, `path::MirrorWalls`, the light
//! interface, `direct::Strata`).
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

use crate::options::{FastPath, RenderOptions};

pub use crate::decision::Decision;

impl Decision {
    /// The reasons every fast path shares for not running: the reference
    /// model runs none, and `--without` leaves one out.
    pub(crate) fn allowed(options: &RenderOptions, path: FastPath, flag: &str) -> Option<Decision> {
        if options.reference {
            Some(Decision::skipped("the reference model runs no fast path"))
        } else if !options.fast_paths.contains(path) {
            Some(Decision::skipped(format!("left out (--without {flag})")))
        } else {
            None
        }
    }
}

/// What the fast paths' declarations read: the options, counts from the
/// scene, and the plan's decisions about the model.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Facts<'a> {
    pub options: &'a RenderOptions,
    pub walls: usize,
    /// How many of the walls are circular arcs.
    pub arcs: usize,
    pub lights: usize,
    pub mirrors: usize,
    pub floor_albedo_walls: usize,
    pub tracing_light: bool,
    pub indirect: bool,
    pub shadows: bool,
    pub floor_memo: bool,
    pub wall_memo: bool,
    pub onward: bool,
    pub light_table: bool,
    /// Wall-light pairs and pixel-light cells: what the coherence masks
    /// would cost.
    pub pairs: usize,
    pub mask_cells: u64,
}

/// The fast paths' decisions for one render.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FastDecisions {
    pub culling: Decision,
    pub coherence: Decision,
    pub strata_loops: Decision,
    pub shortcut: Decision,
    pub tables: Decision,
    pub avx: Decision,
    pub dark_cells: Decision,
}

impl FastDecisions {
    pub(crate) fn of(facts: &Facts) -> FastDecisions {
        FastDecisions {
            culling: culling::supports(facts),
            coherence: coherence::supports(facts),
            strata_loops: strata::supports(facts),
            shortcut: shortcut::supports(facts),
            tables: tables_supports(facts),
            avx: avx_supports(facts),
            dark_cells: dark::supports(facts),
        }
    }
}

/// The floor's albedo along the walls that take it, read from a table the
/// scene builds with itself (`scene::AlbedoAlong`): the same values.
fn tables_supports(facts: &Facts) -> Decision {
    if let Some(no) = Decision::allowed(facts.options, FastPath::Tables, "tables") {
        return no;
    }
    if facts.floor_albedo_walls == 0 {
        return Decision::skipped("no wall takes the floor's albedo");
    }
    Decision::runs("the floor's albedo along the walls that take it, from a table of cells")
}

/// The pixel loop compiled a second time with AVX2: the same operations,
/// so the same bits. Which of the two runs is chosen at run time
/// (`pixel::pixel_fn`), so a plan reads the same on every processor.
fn avx_supports(facts: &Facts) -> Decision {
    if let Some(no) = Decision::allowed(facts.options, FastPath::Avx, "avx") {
        return no;
    }
    Decision::runs(
        "the pixel loop compiled a second time for AVX2, taken where the processor has it (and FLATRAY_PORTABLE is not set)",
    )
}
