//! The direct-light memo of flatray (the original project's "dynamic
//! programming"): direct irradiance on walls, binned along each wall, per
//! side and per light, so that a bounce landing on a wall can read it
//! instead of casting shadow rays.
//!
//! What it is for: a small, thread-safe table that the tracer fills and
//! reads through a narrow interface, so the memo can be switched on and
//! off and benchmarked both ways.
//!
//! What it never does: decide physics (it stores the numbers the tracer
//! gives it), read files, or depend on the order in which threads fill it.
