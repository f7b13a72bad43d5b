//! Whether a part of a render runs, and why: what a fast path or a closed
//! form declares it supports, written once in its own file. The plan keeps
//! it, the render obeys it, and the plan's wording prints its reason.
//!
//! What it never does: decide anything itself.

/// Whether a part of a render runs, and the reason, in words.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Decision {
    pub runs: bool,
    pub why: String,
}

impl Decision {
    pub(crate) fn runs(why: impl Into<String>) -> Decision {
        Decision {
            runs: true,
            why: why.into(),
        }
    }

    pub(crate) fn skipped(why: impl Into<String>) -> Decision {
        Decision {
            runs: false,
            why: why.into(),
        }
    }
}
