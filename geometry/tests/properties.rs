//! Property tests of the geometry layer: random segments and rays, fixed
//! proptest configuration, so each run checks the same cases.

use flatray_geometry::{
    ArcCandidates, DVec2, Kernel, Ray, RayLanes, Segment, SegmentSet, Side, Skip,
    Strategy as Accel, cross, hull_candidates, intersect, reflect,
};
use proptest::prelude::*;

fn coord() -> impl Strategy<Value = f64> {
    prop_oneof![
        -1000.0..1000.0f64,
        // Small integers make shared endpoints, axis-aligned and collinear
        // segments common.
        (-20i32..20).prop_map(|v| v as f64),
    ]
}

fn point() -> impl Strategy<Value = DVec2> {
    (coord(), coord()).prop_map(|(x, y)| DVec2::new(x, y))
}

fn segment() -> impl Strategy<Value = Segment> {
    (point(), point())
        .prop_filter("non-degenerate", |(a, b)| a != b)
        .prop_map(|(a, b)| Segment::new(a, b))
}

fn direction() -> impl Strategy<Value = DVec2> {
    prop_oneof![
        (0.0..std::f64::consts::TAU).prop_map(|a| DVec2::new(a.cos(), a.sin())),
        (-3i32..4, -3i32..4)
            .prop_filter("non-zero", |(x, y)| *x != 0 || *y != 0)
            .prop_map(|(x, y)| DVec2::new(x as f64, y as f64)),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, rng_seed: proptest::test_runner::RngSeed::Fixed(7), ..ProptestConfig::default() })]

    #[test]
    fn a_hit_lies_on_the_ray_and_on_the_segment(seg in segment(), origin in point(), dir in direction()) {
        let ray = Ray::new(origin, dir);
        if let Some(hit) = intersect(&ray, &seg) {
            prop_assert!(hit.t > 0.0);
            prop_assert!((0.0..=1.0).contains(&hit.u));
            let on_ray = ray.at(hit.t);
            let on_segment = seg.point_at(hit.u);
            let scale = 1.0 + origin.abs().max_element() + seg.a.abs().max(seg.b.abs()).max_element();
            prop_assert!(on_ray.distance(on_segment) <= 1e-9 * scale,
                "{on_ray} vs {on_segment}");
        }
    }

    #[test]
    fn a_miss_is_a_miss_for_the_reversed_segment_too(seg in segment(), origin in point(), dir in direction()) {
        let ray = Ray::new(origin, dir);
        let reversed = Segment::new(seg.b, seg.a);
        let forward = intersect(&ray, &seg);
        let backward = intersect(&ray, &reversed);
        prop_assert_eq!(forward.is_some(), backward.is_some());
        if let (Some(f), Some(b)) = (forward, backward) {
            prop_assert!((f.u - (1.0 - b.u)).abs() <= 1e-9);
        }
    }

    #[test]
    fn reflection_preserves_length_and_angle(seg in segment(), dir in direction()) {
        let n = seg.normal();
        let r = reflect(dir, n);
        prop_assert!((r.length() - dir.length()).abs() <= 1e-12 * dir.length());
        // Same angle to the wall on the other side of it.
        prop_assert!((r.dot(n) + dir.dot(n)).abs() <= 1e-12 * dir.length());
        prop_assert!((r.dot(seg.edge()) - dir.dot(seg.edge())).abs() <= 1e-9 * dir.length() * seg.length());
    }

    #[test]
    fn side_tests_agree_with_the_cross_product(seg in segment(), p in point()) {
        let c = cross(seg.b - seg.a, p - seg.a);
        let expected = if c > 0.0 { Some(Side::Positive) } else if c < 0.0 { Some(Side::Negative) } else { None };
        prop_assert_eq!(seg.side_of(p), expected);
    }

    #[test]
    fn the_bvh_and_both_kernels_return_exactly_what_brute_force_returns(
        segments in prop::collection::vec(segment(), 1..200),
        rays in prop::collection::vec((point(), direction(), 0.1..3000.0f64), 20),
        skip in 0u32..200,
    ) {
        let brute = SegmentSet::with_strategy(segments.clone(), Accel::BruteForce);
        let bvh = SegmentSet::with_strategy(segments.clone(), Accel::Bvh);
        // Whatever kernel `brute` detected (AVX on the project's machines),
        // against the scalar one.
        let scalar = SegmentSet::with_strategy(segments.clone(), Accel::BruteForce).with_kernel(Kernel::Scalar);
        prop_assert_eq!(scalar.kernel(), Kernel::Scalar);
        for (origin, dir, t_max) in rays {
            let ray = Ray::new(origin, dir);
            for (t_max, skip) in [(f64::INFINITY, Skip::NONE), (t_max, Skip::one(skip))] {
                // The definition: the nearest `intersect` below t_max, the
                // lower index on a tie.
                let mut reference: Option<(u32, flatray_geometry::Hit)> = None;
                for (i, seg) in segments.iter().enumerate() {
                    if skip.contains(i as u32) {
                        continue;
                    }
                    if let Some(h) = intersect(&ray, seg)
                        && h.t < t_max
                        && reference.is_none_or(|(_, b)| h.t < b.t)
                    {
                        reference = Some((i as u32, h));
                    }
                }
                prop_assert_eq!(brute.closest_hit(&ray, t_max, skip), reference);
                prop_assert_eq!(brute.closest_hit(&ray, t_max, skip), bvh.closest_hit(&ray, t_max, skip));
                prop_assert_eq!(brute.closest_hit(&ray, t_max, skip), scalar.closest_hit(&ray, t_max, skip));
                let mut a = Vec::new();
                brute.for_each_crossing(&ray, t_max, skip, |i, h| { a.push((i, h.t.to_bits(), h.u.to_bits())); true });
                let mut b = Vec::new();
                bvh.for_each_crossing(&ray, t_max, skip, |i, h| { b.push((i, h.t.to_bits(), h.u.to_bits())); true });
                let mut c = Vec::new();
                scalar.for_each_crossing(&ray, t_max, skip, |i, h| { c.push((i, h.t.to_bits(), h.u.to_bits())); true });
                // Brute force visits in index order with either kernel.
                prop_assert_eq!(&a, &c);
                a.sort_unstable();
                b.sort_unstable();
                prop_assert_eq!(a, b);
            }
        }
    }
}

#[test]
fn a_long_corridor_of_segments_builds_a_tree_the_stack_can_walk() {
    // Exponentially spaced segments push a surface-area split towards a
    // deep, list-like tree; the depth bound must keep queries exact.
    let segments: Vec<Segment> = (0..3000)
        .map(|k| {
            let x = 1.001f64.powi(k);
            Segment::new(DVec2::new(x, -1.0), DVec2::new(x, 1.0))
        })
        .collect();
    let brute = SegmentSet::with_strategy(segments.clone(), Accel::BruteForce);
    let bvh = SegmentSet::with_strategy(segments, Accel::Bvh);
    for k in 0..50 {
        let ray = Ray::new(
            DVec2::new(-5.0 + k as f64 * 0.5, 0.3),
            DVec2::new(1.0, 0.001 * k as f64),
        );
        assert_eq!(
            brute.closest_hit(&ray, f64::INFINITY, Skip::NONE),
            bvh.closest_hit(&ray, f64::INFINITY, Skip::NONE)
        );
        let count = |set: &SegmentSet| {
            let mut n = 0;
            set.for_each_crossing(&ray, f64::INFINITY, Skip::NONE, |_, _| {
                n += 1;
                true
            });
            n
        };
        assert_eq!(count(&brute), count(&bvh));
    }
}

#[test]
fn ties_at_a_shared_corner_go_to_the_lower_index_in_every_set() {
    // Thirteen walls meet at the origin (so a ray through it crosses them
    // all at the same `t`), in every lane of several blocks, between
    // walls that lie nearer or farther on the ray.
    let mut segments: Vec<Segment> = (0..13)
        .map(|k| {
            let angle = 0.3 + k as f64 * 0.4;
            Segment::new(DVec2::ZERO, DVec2::new(angle.cos(), angle.sin()) * 5.0)
        })
        .collect();
    segments.push(Segment::new(DVec2::new(3.0, -1.0), DVec2::new(3.0, 1.0)));
    segments.insert(0, Segment::new(DVec2::new(9.0, -1.0), DVec2::new(9.0, 1.0)));
    let ray = Ray::new(DVec2::new(-4.0, 0.0), DVec2::new(1.0, 0.0));
    let sets = [
        SegmentSet::with_strategy(segments.clone(), Accel::BruteForce),
        SegmentSet::with_strategy(segments.clone(), Accel::BruteForce).with_kernel(Kernel::Scalar),
        SegmentSet::with_strategy(segments.clone(), Accel::Bvh),
    ];
    for skip in [Skip::NONE, Skip::one(1), Skip(1, 2)] {
        let expected = if skip == Skip::NONE {
            1
        } else if skip == Skip::one(1) {
            2
        } else {
            3
        };
        for set in &sets {
            let hit = set.closest_hit(&ray, f64::INFINITY, skip);
            assert_eq!(
                hit.map(|(i, h)| (i, h.t)),
                Some((expected, 4.0)),
                "{:?}",
                set.kernel()
            );
            // In lanes, over the list of the walls not skipped.
            let candidates: Vec<u32> = (0..set.len() as u32)
                .filter(|&i| !skip.contains(i))
                .collect();
            let (o, d) = (ray.origin, ray.dir);
            let lanes = RayLanes {
                ox: [o.x; 8],
                oy: [o.y; 8],
                dx: [d.x; 8],
                dy: [d.y; 8],
            };
            let hits = set.closest_hits_among(&lanes, &candidates);
            assert_eq!(std::array::from_fn(|k| hits.hit(k)), [hit; 8]);
            // One ray, the list in lanes.
            assert_eq!(set.closest_hit_among_wide(&ray, &candidates).hit(0), hit);
        }
    }
}

/// A direction at fraction `f` of the way through arc `k` of `arcs`.
fn in_arc(k: usize, arcs: usize, f: f64) -> DVec2 {
    let angle = std::f64::consts::TAU * (k as f64 + f) / arcs as f64;
    DVec2::new(angle.cos(), angle.sin())
}

/// The side of a box rays leave from: large, one pixel, tiny.
fn box_size() -> impl Strategy<Value = f64> {
    prop_oneof![0.5..40.0f64, Just(1.0), Just(1e-6)]
}

/// 64 rays leaving a box: where in it (`x`, `y` as fractions of its
/// sides, often on its edges and corners), in which of up to 64 arcs, and
/// where in the arc (often at its ends).
fn rays_from_box() -> impl Strategy<Value = Vec<(f64, f64, usize, f64)>> {
    let edge_or_inside = || prop_oneof![Just(0.0), Just(1.0), 0.0..1.0f64];
    prop::collection::vec(
        (
            edge_or_inside(),
            edge_or_inside(),
            0usize..64,
            prop_oneof![Just(0.0), Just(1.0 - 1e-12), 0.0..1.0f64],
        ),
        64,
    )
}

/// Short segments around the box `[lo, lo + size]`, where culling decides
/// most, with random long ones.
fn segments_near(lo: DVec2, size: f64) -> impl Strategy<Value = Vec<Segment>> {
    let near =
        (-3.0..4.0f64, -3.0..4.0f64, -1.0..1.0f64, -1.0..1.0f64).prop_map(move |(x, y, dx, dy)| {
            let a = lo + DVec2::new(x, y) * size;
            Segment::new(a, a + DVec2::new(dx, dy) * size)
        });
    prop::collection::vec(prop_oneof![3 => near, 1 => segment()], 1..40)
        .prop_map(|s| s.into_iter().filter(|s| s.a != s.b).collect())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 500, rng_seed: proptest::test_runner::RngSeed::Fixed(11), ..ProptestConfig::default() })]

    #[test]
    fn culled_queries_return_exactly_what_the_full_scan_returns(
        (lo, size, segments) in (point(), box_size())
            .prop_flat_map(|(lo, size)| (Just(lo), Just(size), segments_near(lo, size))),
        arcs in prop_oneof![Just(8usize), Just(16), Just(64)],
        rays in rays_from_box(),
    ) {
        let set = SegmentSet::new(segments);
        let hi = lo + DVec2::splat(size);
        let mut tile = ArcCandidates::default();
        tile.fill(&set, lo, hi, arcs, None);
        // A quarter of the box, filled from the whole box's lists.
        let mut quarter = ArcCandidates::default();
        let mid = lo + DVec2::splat(size / 2.0);
        quarter.fill(&set, lo, mid, arcs, Some(&tile));
        prop_assert_eq!(tile.arcs(), arcs);
        for (fx, fy, k, f) in rays {
            let k = k % arcs;
            let dir = in_arc(k, arcs, f);
            for (candidates, from, to) in [(&tile, lo, hi), (&quarter, lo, mid)] {
                let origin = DVec2::new(from.x + fx * (to.x - from.x), from.y + fy * (to.y - from.y));
                let ray = Ray::new(origin, dir);
                let list = candidates.arc(k);
                prop_assert!(list.windows(2).all(|w| w[0] < w[1]));
                prop_assert_eq!(
                    set.closest_hit_among(&ray, f64::INFINITY, Skip::NONE, list),
                    set.closest_hit(&ray, f64::INFINITY, Skip::NONE),
                    "arc {} of {}, origin {}, dir {}", k, arcs, origin, dir
                );
                // Every crossing, not only the nearest, is a candidate.
                set.for_each_crossing(&ray, f64::INFINITY, Skip::NONE, |i, _| {
                    assert!(list.contains(&i), "wall {i} crossed but culled");
                    true
                });
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1000, rng_seed: proptest::test_runner::RngSeed::Fixed(13), ..ProptestConfig::default() })]

    /// Eight rays in lanes against a list of candidates: lane by lane, the
    /// answer of the one-ray query over the same list. Origins are often
    /// segment ends (shared corners, rays along segments) and directions
    /// small integer vectors (parallel to the segments often).
    #[test]
    fn rays_in_lanes_hit_what_each_ray_hits_alone(
        segments in prop::collection::vec(segment(), 1..24),
        keep in prop::collection::vec(any::<bool>(), 24),
        rays in prop::collection::vec((0usize..3, 0usize..24, point(), direction()), 8),
    ) {
        let origins: Vec<DVec2> = rays
            .iter()
            .map(|&(kind, k, p, _)| match kind {
                0 => segments[k % segments.len()].a,
                1 => segments[k % segments.len()].b,
                _ => p,
            })
            .collect();
        let set = SegmentSet::new(segments);
        // An ascending list, as culling makes them: some of the segments.
        let candidates: Vec<u32> = (0..set.len() as u32).filter(|&i| keep[i as usize]).collect();
        let mut lanes = RayLanes { ox: [0.0; 8], oy: [0.0; 8], dx: [0.0; 8], dy: [0.0; 8] };
        for (k, (o, &(_, _, _, d))) in origins.iter().zip(&rays).enumerate() {
            (lanes.ox[k], lanes.oy[k], lanes.dx[k], lanes.dy[k]) = (o.x, o.y, d.x, d.y);
        }
        // The AVX kernel where the processor has it, and the portable one.
        let scalar = set.clone().with_kernel(Kernel::Scalar);
        for (hits, kernel) in [
            (set.closest_hits_among(&lanes, &candidates), set.kernel()),
            (scalar.closest_hits_among(&lanes, &candidates), Kernel::Scalar),
        ] {
            for k in 0..8 {
                let ray = lanes.ray(k);
                prop_assert_eq!(ray, Ray::new(origins[k], rays[k].3));
                prop_assert_eq!(
                    hits.hit(k),
                    set.closest_hit_among(&ray, f64::INFINITY, Skip::NONE, &candidates),
                    "lane {}, {:?}", k, kernel
                );
            }
        }
        // Fewer lanes than a register holds (one or two samples of an
        // arc): the same answers, lane by lane.
        for set in [&set, &scalar] {
            let one = first_lanes::<1>(&lanes);
            let two = first_lanes::<2>(&lanes);
            let four = first_lanes::<4>(&lanes);
            let hits = set.closest_hits_among(&one, &candidates);
            prop_assert_eq!(hits.hit(0), set.closest_hit_among(&one.ray(0), f64::INFINITY, Skip::NONE, &candidates));
            // One ray, its candidates in lanes: each of the eight rays.
            for k in 0..8 {
                let ray = lanes.ray(k);
                let wide = set.closest_hit_among_wide(&ray, &candidates);
                prop_assert_eq!(wide.hit(0), set.closest_hit_among(&ray, f64::INFINITY, Skip::NONE, &candidates), "lane {}", k);
            }
            let hits = set.closest_hits_among(&two, &candidates);
            for k in 0..2 {
                prop_assert_eq!(hits.hit(k), set.closest_hit_among(&two.ray(k), f64::INFINITY, Skip::NONE, &candidates));
            }
            let hits = set.closest_hits_among(&four, &candidates);
            for k in 0..4 {
                prop_assert_eq!(hits.hit(k), set.closest_hit_among(&four.ray(k), f64::INFINITY, Skip::NONE, &candidates));
            }
        }
    }
}

/// The first `N` of eight lanes.
fn first_lanes<const N: usize>(lanes: &RayLanes<8>) -> RayLanes<N> {
    RayLanes {
        ox: std::array::from_fn(|k| lanes.ox[k]),
        oy: std::array::from_fn(|k| lanes.oy[k]),
        dx: std::array::from_fn(|k| lanes.dx[k]),
        dy: std::array::from_fn(|k| lanes.dy[k]),
    }
}

/// A room around the box `[lo, lo + size]`: four walls, each perhaps
/// with a door, at one to three box sizes away, turned by `turn`; with
/// short segments inside and outside it and some long ones.
fn room_around(lo: DVec2, size: f64) -> impl Strategy<Value = Vec<Segment>> {
    let centre = lo + DVec2::splat(size / 2.0);
    (
        prop::collection::vec(
            (
                1.0..3.0f64,
                prop_oneof![Just(None), (0.1..0.8f64).prop_map(Some)],
            ),
            4,
        ),
        prop_oneof![Just(0.0), -0.5..0.5f64],
        segments_near(lo - DVec2::splat(2.0 * size), 2.0 * size),
    )
        .prop_map(move |(sides, turn, mut others)| {
            let (sin, cos) = turn.sin_cos();
            let rotate =
                |v: DVec2| centre + DVec2::new(v.x * cos - v.y * sin, v.x * sin + v.y * cos) * size;
            let r: Vec<f64> = sides.iter().map(|s| s.0 + 0.5).collect();
            let corners = [
                DVec2::new(-r[3], -r[0]),
                DVec2::new(r[1], -r[0]),
                DVec2::new(r[1], r[2]),
                DVec2::new(-r[3], r[2]),
            ];
            let mut walls = Vec::new();
            for (k, &(_, door)) in sides.iter().enumerate() {
                let (p, q) = (corners[k], corners[(k + 1) % 4]);
                match door {
                    None => walls.push(Segment::new(rotate(p), rotate(q))),
                    Some(at) => {
                        walls.push(Segment::new(rotate(p), rotate(p + (q - p) * at)));
                        walls.push(Segment::new(rotate(p + (q - p) * (at + 0.15)), rotate(q)));
                    }
                }
            }
            walls.append(&mut others);
            walls.into_iter().filter(|s| s.a != s.b).collect()
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 500, rng_seed: proptest::test_runner::RngSeed::Fixed(17), ..ProptestConfig::default() })]

    /// Lists without what blocking segments hide still give every ray
    /// from the box its closest hit, and so on along its line through
    /// every segment that does not block, to the first that does.
    #[test]
    fn lists_without_blocked_segments_give_the_closest_hits_along_the_line(
        (lo, size, segments) in (point(), box_size())
            .prop_flat_map(|(lo, size)| (Just(lo), Just(size), room_around(lo, size))),
        blocking in prop::collection::vec(prop::bool::weighted(0.8), 64),
        arcs in prop_oneof![Just(8usize), Just(16), Just(64)],
        rays in rays_from_box(),
    ) {
        let set = SegmentSet::new(segments);
        let blocks = |i: u32| blocking[i as usize % blocking.len()];
        let hi = lo + DVec2::splat(size);
        let mut lists = ArcCandidates::default();
        lists.fill(&set, lo, hi, arcs, None);
        let before: usize = (0..arcs).map(|k| lists.arc(k).len()).sum();
        lists.drop_blocked(&set, lo, hi, blocks);
        let after: usize = (0..arcs).map(|k| lists.arc(k).len()).sum();
        prop_assert!(after <= before);
        for (fx, fy, k, f) in rays {
            let k = k % arcs;
            let list = lists.arc(k);
            prop_assert!(list.windows(2).all(|w| w[0] < w[1]));
            let origin = DVec2::new(lo.x + fx * size, lo.y + fy * size);
            let mut ray = Ray::new(origin, in_arc(k, arcs, f));
            let mut skip = Skip::NONE;
            for _ in 0..16 {
                let culled = set.closest_hit_among(&ray, f64::INFINITY, skip, list);
                let full = set.closest_hit(&ray, f64::INFINITY, skip);
                prop_assert_eq!(culled, full, "arc {} of {}, ray {:?}", k, arcs, ray);
                match full {
                    Some((index, hit)) if !blocks(index) => {
                        ray = Ray::new(ray.at(hit.t), ray.dir);
                        skip = Skip::one(index);
                    }
                    _ => break,
                }
            }
        }
    }
}

#[test]
fn a_closed_room_hides_what_lies_beyond_its_walls() {
    // A unit box in a closed square room, with walls beyond it on every
    // side: only the room's own walls stay, unless a wall lets rays pass.
    let walls = vec![
        Segment::new(DVec2::new(10.0, -10.0), DVec2::new(10.0, 10.0)),
        Segment::new(DVec2::new(-10.0, 10.0), DVec2::new(10.0, 10.0)),
        Segment::new(DVec2::new(-10.0, -10.0), DVec2::new(-10.0, 10.0)),
        Segment::new(DVec2::new(-10.0, -10.0), DVec2::new(10.0, -10.0)),
        Segment::new(DVec2::new(20.0, -1.0), DVec2::new(20.0, 1.0)),
        Segment::new(DVec2::new(-20.0, -1.0), DVec2::new(-20.0, 1.0)),
    ];
    let set = SegmentSet::new(walls);
    let (lo, hi) = (DVec2::splat(-0.5), DVec2::splat(0.5));
    let mut c = ArcCandidates::default();
    c.fill(&set, lo, hi, 16, None);
    assert_eq!(c.arc(0), &[0, 4]);
    c.drop_blocked(&set, lo, hi, |_| true);
    assert_eq!(c.arc(0), &[0]);
    assert_eq!(c.arc(8), &[2]);
    // The right wall lets light through: the segment beyond it stays.
    c.fill(&set, lo, hi, 16, None);
    c.drop_blocked(&set, lo, hi, |i| i != 0);
    assert_eq!(c.arc(0), &[0, 4]);
    assert_eq!(c.arc(8), &[2]);
}

#[test]
fn culling_keeps_only_the_walls_an_arc_can_see() {
    // A unit box in the middle of four walls: rays going right (the arc
    // around angle 0) can meet only the right wall, rays going down only
    // the bottom one (y grows downwards, angles turn from +x to +y).
    let walls = vec![
        Segment::new(DVec2::new(10.0, -10.0), DVec2::new(10.0, 10.0)),
        Segment::new(DVec2::new(-10.0, 10.0), DVec2::new(10.0, 10.0)),
        Segment::new(DVec2::new(-10.0, -10.0), DVec2::new(-10.0, 10.0)),
        Segment::new(DVec2::new(-10.0, -10.0), DVec2::new(10.0, -10.0)),
    ];
    let set = SegmentSet::new(walls);
    let mut c = ArcCandidates::default();
    c.fill(&set, DVec2::splat(-0.5), DVec2::splat(0.5), 16, None);
    assert_eq!(c.arc(0), &[0]);
    assert_eq!(c.arc(15), &[0]);
    assert_eq!(c.arc(4), &[1]);
    assert_eq!(c.arc(8), &[2]);
    assert_eq!(c.arc(12), &[3]);
    // An arc that reaches a corner lists both walls of it.
    assert_eq!(c.arc(2), &[0, 1]);
    // Arcs beyond those filled are empty.
    assert!(c.arc(16).is_empty());
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 500, rng_seed: proptest::test_runner::RngSeed::Fixed(13), ..ProptestConfig::default() })]

    #[test]
    fn shadow_rays_among_hull_candidates_cross_what_the_full_scan_crosses(
        (lo, size, segments) in (point(), prop_oneof![0.5..40.0f64, Just(4.0), Just(1e-6)])
            .prop_flat_map(|(lo, size)| (Just(lo), Just(size), segments_near(lo, size))),
        light in (point(), prop_oneof![Just(None), point().prop_map(Some)]),
        rays in prop::collection::vec(
            (prop_oneof![Just(0.0), Just(1.0), 0.0..1.0f64], prop_oneof![Just(0.0), Just(1.0), 0.0..1.0f64],
             prop_oneof![Just(0.0), Just(1.0), 0.0..1.0f64]),
            32),
    ) {
        // Brute force visits crossings in index order, as the culled scan
        // does (a BVH visits them in tree order).
        let set = SegmentSet::with_strategy(segments, Accel::BruteForce);
        let hi = lo + DVec2::splat(size);
        let (a, b) = (light.0, light.1.unwrap_or(light.0));
        let mut points = vec![lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y), a];
        if light.1.is_some() {
            points.push(b);
        }
        let mut list = Vec::new();
        hull_candidates(&set, &points, &mut list);
        prop_assert!(list.windows(2).all(|w| w[0] < w[1]));
        for (fx, fy, f) in rays {
            let origin = DVec2::new(lo.x + fx * size, lo.y + fy * size);
            let target = a + f * (b - a);
            // As a shadow ray is cast: to the target, up to t = 1.
            let ray = Ray::new(origin, target - origin);
            let mut all = Vec::new();
            set.for_each_crossing(&ray, 1.0, Skip::NONE, |i, h| { all.push((i, h.t.to_bits(), h.u.to_bits())); true });
            let mut among = Vec::new();
            set.for_each_crossing_among(&ray, 1.0, Skip::NONE, &list, |i, h| { among.push((i, h.t.to_bits(), h.u.to_bits())); true });
            prop_assert_eq!(among, all, "origin {}, target {}", origin, target);
        }
    }
}

#[test]
fn hull_culling_keeps_only_the_walls_between_a_box_and_a_light() {
    // A unit box, a light to its right: a wall between them is kept, walls
    // behind the box, beyond the light or off to the side are not.
    let walls = vec![
        Segment::new(DVec2::new(5.0, -1.0), DVec2::new(5.0, 1.0)),
        Segment::new(DVec2::new(-3.0, -1.0), DVec2::new(-3.0, 1.0)),
        Segment::new(DVec2::new(12.0, -1.0), DVec2::new(12.0, 1.0)),
        Segment::new(DVec2::new(5.0, 4.0), DVec2::new(6.0, 6.0)),
    ];
    let set = SegmentSet::new(walls);
    let mut list = Vec::new();
    let box_and_light = [
        DVec2::splat(-0.5),
        DVec2::new(0.5, -0.5),
        DVec2::splat(0.5),
        DVec2::new(-0.5, 0.5),
        DVec2::new(10.0, 0.0),
    ];
    hull_candidates(&set, &box_and_light, &mut list);
    assert_eq!(list, [0]);
    // A line light reaching up past the fourth wall keeps it too.
    let mut with_line = box_and_light.to_vec();
    with_line.push(DVec2::new(10.0, 9.0));
    hull_candidates(&set, &with_line, &mut list);
    assert_eq!(list, [0, 3]);
    // Too many points, or one not finite: nothing is culled.
    let many = vec![DVec2::ZERO; flatray_geometry::MAX_HULL_POINTS + 1];
    hull_candidates(&set, &many, &mut list);
    assert_eq!(list, [0, 1, 2, 3]);
    hull_candidates(&set, &[DVec2::ZERO, DVec2::new(f64::NAN, 0.0)], &mut list);
    assert_eq!(list, [0, 1, 2, 3]);
    // Repeated and collinear points: a segment's hull.
    let line = [
        DVec2::ZERO,
        DVec2::new(10.0, 0.0),
        DVec2::new(5.0, 0.0),
        DVec2::ZERO,
    ];
    hull_candidates(&set, &line, &mut list);
    assert_eq!(list, [0]);
}

#[test]
fn rays_in_lanes_break_ties_as_each_ray_alone() {
    // Four walls through (5, 5), and eight rays through that point from
    // grid points: small integers, so every crossing there is at t = 1
    // exactly, a tie that the lower index wins.
    let p = DVec2::new(5.0, 5.0);
    let walls = [
        ((3.0, 5.0), (7.0, 5.0)),
        ((5.0, 3.0), (5.0, 7.0)),
        ((3.0, 3.0), (7.0, 7.0)),
        ((3.0, 7.0), (7.0, 3.0)),
    ];
    let set = SegmentSet::new(
        walls
            .iter()
            .map(|&((ax, ay), (bx, by))| Segment::new(DVec2::new(ax, ay), DVec2::new(bx, by)))
            .collect(),
    );
    let origins = [
        (1.0, 2.0),
        (9.0, 2.0),
        (1.0, 8.0),
        (9.0, 8.0),
        (2.0, 1.0),
        (8.0, 1.0),
        (2.0, 9.0),
        (8.0, 9.0),
    ];
    let mut lanes = RayLanes {
        ox: [0.0; 8],
        oy: [0.0; 8],
        dx: [0.0; 8],
        dy: [0.0; 8],
    };
    for (k, &(x, y)) in origins.iter().enumerate() {
        (lanes.ox[k], lanes.oy[k]) = (x, y);
        (lanes.dx[k], lanes.dy[k]) = (p.x - x, p.y - y);
    }
    for candidates in [vec![0, 1, 2, 3], vec![1, 2, 3], vec![2, 3]] {
        for set in [set.clone(), set.clone().with_kernel(Kernel::Scalar)] {
            let hits = set.closest_hits_among(&lanes, &candidates);
            for k in 0..8 {
                let alone =
                    set.closest_hit_among(&lanes.ray(k), f64::INFINITY, Skip::NONE, &candidates);
                assert_eq!(alone.map(|(_, h)| h.t), Some(1.0), "lane {k}");
                assert_eq!(alone.map(|(i, _)| i), Some(candidates[0]), "lane {k}");
                assert_eq!(hits.hit(k), alone, "lane {k}, {:?}", set.kernel());
            }
            // One and two lanes take another loop.
            let one = set.closest_hits_among(&first_lanes::<1>(&lanes), &candidates);
            let two = set.closest_hits_among(&first_lanes::<2>(&lanes), &candidates);
            assert_eq!(one.hit(0), hits.hit(0), "{:?}", set.kernel());
            assert_eq!([two.hit(0), two.hit(1)], [hits.hit(0), hits.hit(1)]);
        }
    }
}
