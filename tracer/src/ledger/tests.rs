//! The proof by enumeration: every class of light path up to six events,
//! for every kind of light and every combination of the plan's decisions,
//! is counted exactly once by the estimators, each estimator read through
//! the ledger's rules as its loop reads them.

use super::*;

/// One step of a light path, from the light towards the floor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Step {
    Specular(Event),
    Wall(Vertex),
}

const STEPS: [Step; 7] = [
    Step::Specular(Event::FlatMirror),
    Step::Specular(Event::CurvedMirror),
    Step::Specular(Event::GlassIn),
    Step::Specular(Event::GlassOut),
    Step::Specular(Event::GlassReflect),
    Step::Wall(Vertex::Diffuse),
    Step::Wall(Vertex::Glossy),
];

/// A class of paths: a light, its steps in light order, then the floor.
#[derive(Clone, Debug)]
struct Class {
    light: LightKind,
    steps: Vec<Step>,
}

impl Class {
    /// The non-specular vertices in light order, each with the run of
    /// specular events before it (light order), the floor last.
    fn vertices(&self) -> Vec<(Vertex, Run)> {
        let mut out = Vec::new();
        let mut run = Run::EMPTY;
        for step in &self.steps {
            match *step {
                Step::Specular(e) => run = run.with(e),
                Step::Wall(v) => {
                    out.push((v, run));
                    run = Run::EMPTY;
                }
            }
        }
        out.push((Vertex::Floor, run));
        out
    }

    /// Walls on the path: diffuse and glossy reflections.
    fn reflections(&self) -> u32 {
        self.steps
            .iter()
            .filter(|s| matches!(s, Step::Wall(_)))
            .count() as u32
    }
}

/// What the estimators count of a class: whole shares, and the two halves
/// of a shared one.
#[derive(Debug, Default, PartialEq, Eq)]
struct Count {
    all: Vec<&'static str>,
    light: u32,
    lobe: u32,
}

impl Count {
    fn add(&mut self, name: &'static str, share: Share) {
        match share {
            Share::None => {}
            Share::All => self.all.push(name),
            Share::Light => self.light += 1,
            Share::Lobe => self.lobe += 1,
        }
    }

    /// Whether the class is counted exactly once: one estimator whole, or
    /// one pair of weights that sum to one.
    fn once(&self) -> bool {
        (self.all.len() == 1 && self.light == 0 && self.lobe == 0)
            || (self.all.is_empty() && self.light == 1 && self.lobe == 1)
    }

    fn zero(&self) -> bool {
        self.all.is_empty() && self.light == 0 && self.lobe == 0
    }
}

/// Every estimator's share of `class`, each as its loop decides it.
fn count(ledger: Ledger, class: &Class) -> Count {
    let mut count = Count::default();
    let vertices = class.vertices();
    let walls = vertices.len() as u32 - 1;
    // A path from the floor meets the walls in reverse order: the wall
    // `k` in light order is its reflection `walls - k`.
    let path_reflections = |k: usize| walls - k as u32;

    // Next-event estimation (shadow rays and the closed forms) at the
    // first non-specular vertex from the light, if the path from the floor
    // reaches it within its reflections.
    let (at, run) = vertices[0];
    let d = if at == Vertex::Floor {
        0
    } else {
        path_reflections(0)
    };
    if d <= ledger.bounces {
        let share = if run.is_specular() {
            match ledger.closed_form(class.light, run, at) {
                true => Share::All,
                false => Share::None,
            }
        } else if at == Vertex::Glossy && class.light == LightKind::Aimed {
            // As the path loop asks it (`path::glossy_direct`).
            match ledger.glossy_leaves_aimed(d) {
                true => Share::None,
                false => Share::All,
            }
        } else {
            ledger.straight(class.light, at, d == 1)
        };
        count.add("next-event estimation", share);
    }

    // A path ray that meets the light (lines and circles only), after the
    // path took every vertex of the class.
    if class.light == LightKind::Area && walls <= ledger.bounces {
        count.add("path ray", ledger.path_meets(run, at));
    }

    // The caustic pass: photons from the light, followed as
    // `light_tracer::follow_photon` follows them.
    let photons = ledger.caustics
        && match class.light {
            LightKind::Area => ledger.area_photons,
            LightKind::Aimed | LightKind::Laser => true,
        };
    if photons {
        let mut photon = Photon {
            area: class.light == LightKind::Area,
            unseen: class.light == LightKind::Laser,
            ..Photon::default()
        };
        let mut reflections = 0;
        for step in &class.steps {
            match *step {
                Step::Specular(e) => photon.run = photon.run.with(e),
                Step::Wall(v) => {
                    // A photon that stops here ends the walk: `k` is its
                    // wall in light order.
                    let k = reflections as usize;
                    match ledger.photon_at(&photon, v) {
                        AtWall::Bin { level } => {
                            let d = path_reflections(k);
                            if d <= ledger.bounces && ledger.reads_bins(level, d) {
                                count.add("caustic bins", Share::All);
                            }
                            return count;
                        }
                        AtWall::Stop => return count,
                        AtWall::Scatter => {
                            if reflections == ledger.bounces {
                                return count;
                            }
                            reflections += 1;
                            photon = match v {
                                Vertex::Glossy => ledger.photon_glossy(photon),
                                _ => Photon {
                                    run: Run::EMPTY,
                                    ..photon
                                },
                            };
                        }
                    }
                }
            }
        }
        if ledger.photon_lights_floor(&photon) {
            count.add("caustic floor", Share::All);
        }
    }
    count
}

/// Every class of up to `n` steps, for every light.
fn classes(n: usize) -> Vec<Class> {
    let mut out = Vec::new();
    let mut steps: Vec<Vec<Step>> = vec![Vec::new()];
    for _ in 0..=n {
        let mut next = Vec::new();
        for s in &steps {
            for light in [LightKind::Aimed, LightKind::Laser, LightKind::Area] {
                out.push(Class {
                    light,
                    steps: s.clone(),
                });
            }
            for step in STEPS {
                let mut longer = s.clone();
                longer.push(step);
                next.push(longer);
            }
        }
        steps = next;
    }
    out
}

/// Every combination of the plan's decisions that a plan can make: the
/// caustic pass runs wherever photons take a path (as `Plan::new` decides
/// it, `--caustics on`), and area photons only with it.
fn ledgers() -> Vec<Ledger> {
    let mut out = Vec::new();
    for bounces in 0..=3 {
        for bits in 0..16u32 {
            out.push(Ledger {
                mirror_lights: bits & 1 != 0,
                glass_lights: bits & 2 != 0,
                area_photons: bits & 4 != 0,
                aimed_mirrors: bits & 8 != 0,
                caustics: true,
                bounces,
            });
        }
    }
    out
}

#[test]
fn every_path_class_up_to_six_events_is_counted_exactly_once() {
    let classes = classes(6);
    let mut walked = 0u64;
    let mut failures = Vec::new();
    let mut wrong = 0u64;
    for ledger in ledgers() {
        for class in &classes {
            walked += 1;
            let count = count(ledger, class);
            let within = class.reflections() <= ledger.bounces;
            let right = if within { count.once() } else { count.zero() };
            if !right {
                wrong += 1;
                if failures.len() < 8 {
                    failures.push(format!("{ledger:?} {class:?}: {count:?}"));
                }
            }
        }
    }
    // 3 lights times (7^0 + ... + 7^6) step lists, times 64 ledgers.
    assert_eq!(walked, 3 * 137_257 * 64);
    assert!(
        failures.is_empty(),
        "{wrong} of {walked} wrong, among them:\n{}",
        failures.join("\n")
    );
}

#[test]
fn a_point_seen_in_a_mirror_off_two_rough_mirrors_is_counted_by_the_photons() {
    // The class no estimator counted while photons stopped at their
    // second rough mirror.
    let ledger = Ledger {
        caustics: true,
        bounces: 2,
        ..Ledger::default()
    };
    let class = Class {
        light: LightKind::Aimed,
        steps: vec![
            Step::Specular(Event::FlatMirror),
            Step::Wall(Vertex::Glossy),
            Step::Wall(Vertex::Glossy),
        ],
    };
    assert_eq!(count(ledger, &class).all, vec!["caustic floor"]);
    // And a laser's light off two rough mirrors, which no path finds.
    let laser = Class {
        light: LightKind::Laser,
        steps: vec![Step::Wall(Vertex::Glossy), Step::Wall(Vertex::Glossy)],
    };
    assert_eq!(count(ledger, &laser).all, vec!["caustic floor"]);
}

#[test]
fn without_the_caustic_pass_only_what_photons_take_goes_uncounted() {
    // `--caustics off`: points, spots and suns after mirrors and glass,
    // and lasers, are left out (the plan says so); everything else is
    // still counted once.
    let ledger = Ledger {
        caustics: false,
        bounces: 2,
        ..Ledger::default()
    };
    for class in classes(4) {
        let count = count(ledger, &class);
        if class.reflections() > ledger.bounces {
            assert!(count.zero(), "{class:?}: {count:?}");
            continue;
        }
        let photons_only = class.light == LightKind::Laser
            || (class.light == LightKind::Aimed && class.vertices()[0].1.is_specular());
        assert_eq!(count.once(), !photons_only, "{class:?}: {count:?}");
    }
}

#[test]
fn a_point_in_one_flat_mirror_is_counted_by_its_closed_form_or_by_photons() {
    let class = |steps: Vec<Step>| Class {
        light: LightKind::Aimed,
        steps,
    };
    let mirror = Step::Specular(Event::FlatMirror);
    let diffuse = Step::Wall(Vertex::Diffuse);
    for bounces in 0..=2 {
        let photons = Ledger {
            caustics: true,
            bounces,
            ..Ledger::default()
        };
        let closed = Ledger {
            aimed_mirrors: true,
            ..photons
        };
        // To the floor, and to a diffuse wall that lights the floor.
        let floor = class(vec![mirror]);
        assert_eq!(count(photons, &floor).all, vec!["caustic floor"]);
        assert_eq!(count(closed, &floor).all, vec!["next-event estimation"]);
        if bounces > 0 {
            let wall = class(vec![mirror, diffuse]);
            assert_eq!(count(photons, &wall).all, vec!["caustic bins"]);
            assert_eq!(count(closed, &wall).all, vec!["next-event estimation"]);
        }
        // Two mirrors, or a mirror then glass: still the photons'.
        for second in [mirror, Step::Specular(Event::GlassIn)] {
            let two = class(vec![mirror, second]);
            assert_eq!(count(closed, &two).all, vec!["caustic floor"]);
        }
        // Without the caustic pass the closed form still counts it.
        let alone = Ledger {
            caustics: false,
            ..closed
        };
        assert_eq!(count(alone, &floor).all, vec!["next-event estimation"]);
    }
}

#[test]
fn a_run_remembers_its_one_event_only() {
    let one = Run::EMPTY.with(Event::FlatMirror);
    assert_eq!(one.only, Some(Event::FlatMirror));
    let two = one.with(Event::FlatMirror);
    assert_eq!((two.events, two.only), (2, None));
    assert!(!Run::EMPTY.is_specular() && one.is_specular());
    assert_eq!(Event::GlassIn.reversed(), Event::GlassOut);
}

#[test]
fn where_every_mirror_lies_on_one_line_the_closed_form_leaves_photons_nothing() {
    // A scene whose only specular walls are flat mirrors on one line
    // (`ClosedForms::take_aimed_runs`): no run holds more than one event,
    // and that one a flat mirror. Without rough mirrors and lasers the
    // plan then runs no caustic pass, and every class such a scene has is
    // still counted once.
    let possible = |class: &Class| {
        class.light != LightKind::Laser
            && class.vertices().iter().all(|&(v, run)| {
                v != Vertex::Glossy
                    && (run == Run::EMPTY || run == Run::EMPTY.with(Event::FlatMirror))
            })
    };
    let mut walked = 0;
    for bounces in 0..=3 {
        for bits in 0..2u32 {
            let ledger = Ledger {
                mirror_lights: bits & 1 != 0,
                aimed_mirrors: true,
                caustics: false,
                bounces,
                ..Ledger::default()
            };
            for class in classes(6).iter().filter(|c| possible(c)) {
                walked += 1;
                let count = count(ledger, class);
                let right = match class.reflections() <= bounces {
                    true => count.once(),
                    false => count.zero(),
                };
                assert!(right, "{ledger:?} {class:?}: {count:?}");
            }
        }
    }
    // Two lights times the 53 lists of up to six steps off mirrors and
    // diffuse walls with no two mirrors in a row, times 8 ledgers.
    assert_eq!(walked, 2 * 53 * 8);
    // Without the closed form the same classes need the photons.
    let photons_needed = Ledger {
        caustics: false,
        bounces: 1,
        ..Ledger::default()
    };
    let in_mirror = Class {
        light: LightKind::Aimed,
        steps: vec![Step::Specular(Event::FlatMirror)],
    };
    assert!(count(photons_needed, &in_mirror).zero());
}
