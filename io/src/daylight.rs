//! Daylight: the sun's place in the sky from a date, a local time and a
//! place on Earth (NREL's Solar Position Algorithm), its direction on the
//! canvas, and the frame of line lights that carries a uniform sky.
//!
//! The plane is read as a floor plan under an open sky (`docs/model.md`,
//! "Daylight"): the sun's rays cross the plan along its azimuth, and the
//! floor receives its irradiance times the sine of its elevation. The sky
//! is a uniform radiance arriving from every direction no wall blocks,
//! carried by four one-sided line lights on a frame around the whole
//! scene, each emitting inward with the sky's radiance: a line light of
//! radiance `I` brings exactly `I` per radian of the angle it subtends
//! (flatland falloff), so a point receives `I` times the angle of sky it
//! sees, by every estimator the line lights have.

use flatray_geometry::{DVec2, Segment};
use flatray_tracer::scene::{Canvas, Profile, Wall};
use solar_positioning::time::JulianDate;
use solar_positioning::{Location, RefractionCorrection, SolarPositions};

use crate::format::{Date, TimeOfDay};

/// Where the sun stands, as seen from a place on Earth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SunPlace {
    /// Degrees clockwise from north: 90 is east, 180 south.
    pub azimuth: f64,
    /// Degrees above the horizon (negative below), refraction included.
    pub elevation: f64,
}

/// The air the sun's light is bent by near the horizon, and the clock's
/// lag behind the Earth's turning: what [`sun_place_with`] takes besides
/// the date and the place.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Atmosphere {
    /// Height above sea level, in metres.
    pub height: f64,
    /// Mean air pressure, in millibars.
    pub pressure: f64,
    /// Mean air temperature, in degrees Celsius.
    pub temperature: f64,
    /// Terrestrial time minus universal time, in seconds; `None` for
    /// the estimate of the date (Espenak and Meeus).
    pub delta_t: Option<f64>,
}

impl Default for Atmosphere {
    /// Sea level, 1010 mbar, 10 degrees, the date's estimated delta T.
    fn default() -> Atmosphere {
        Atmosphere {
            height: 0.0,
            pressure: 1010.0,
            temperature: 10.0,
            delta_t: None,
        }
    }
}

/// Where the sun stands at local `time` on `date`, `zone` hours ahead of
/// UTC, at `latitude` and `longitude` (degrees, east positive), at sea
/// level in a standard atmosphere.
pub fn sun_place(
    date: Date,
    time: TimeOfDay,
    zone: f64,
    latitude: f64,
    longitude: f64,
) -> Result<SunPlace, String> {
    sun_place_with(date, time, zone, latitude, longitude, Atmosphere::default())
}

/// Where sun `light` of a scene file stands; `None` when `light` is not a
/// [`LightSpec::Sun`](crate::format::LightSpec::Sun).
pub fn place_of(light: &crate::format::LightSpec) -> Option<Result<SunPlace, String>> {
    match *light {
        crate::format::LightSpec::Sun {
            date,
            time,
            zone,
            latitude,
            longitude,
            ..
        } => Some(sun_place(date, time, zone.0, latitude.0, longitude.0)),
        _ => None,
    }
}

/// [`sun_place`] in the given atmosphere.
pub fn sun_place_with(
    date: Date,
    time: TimeOfDay,
    zone: f64,
    latitude: f64,
    longitude: f64,
    air: Atmosphere,
) -> Result<SunPlace, String> {
    let failed = |e: solar_positioning::Error| format!("the sun's position: {e}");
    let delta_t = match air.delta_t {
        Some(d) => d,
        None => {
            solar_positioning::delta_t::estimate_from_date(date.year, date.month).map_err(failed)?
        }
    };
    // The local clock's reading as if it were UTC, then moved by the zone.
    let local = JulianDate::from_utc(
        date.year,
        date.month,
        date.day,
        time.hour,
        time.minute,
        time.second as f64,
        delta_t,
    )
    .map_err(failed)?;
    let utc = JulianDate::new(local.julian_date() - zone / 24.0, delta_t).map_err(failed)?;
    let refraction = RefractionCorrection::new(air.pressure, air.temperature).map_err(failed)?;
    let place = SolarPositions::new()
        .at_from_julian(
            utc,
            Location {
                latitude,
                longitude,
            },
            air.height,
            Some(refraction),
        )
        .map_err(failed)?;
    Ok(SunPlace {
        azimuth: place.azimuth(),
        elevation: place.elevation_angle(),
    })
}

/// A sky's radiance profile on the canvas: `knots` of an azimuth
/// (degrees clockwise from north) and a factor, with north at `north`
/// degrees clockwise from the canvas's up. A direction of bearing `b`
/// clockwise from up (y growing down) is `(sin b, -cos b)`, of world
/// angle `b - 90` degrees.
pub fn sky_profile(knots: &[(f64, f64)], north: f64) -> Result<Profile, String> {
    let world: Vec<(f64, f64)> = knots
        .iter()
        .map(|&(azimuth, factor)| ((north + azimuth - 90.0).to_radians(), factor))
        .collect();
    Profile::new(&world)
}

/// The direction the sun's rays travel across the canvas (y growing
/// down), for the sun at `azimuth` and north at `north` degrees
/// clockwise from the canvas's up.
pub fn sun_direction(azimuth: f64, north: f64) -> DVec2 {
    // The sun's bearing on the canvas, clockwise from up: up is (0, -1),
    // right (1, 0). The rays travel away from it.
    let (s, c) = (north + azimuth).to_radians().sin_cos();
    DVec2::new(-s, c)
}

/// The four one-sided line lights that carry a sky around `canvas` and
/// `walls`: a rectangle enclosing both with a margin, each side emitting
/// inward (to the right of `a -> b` with y growing down).
pub(crate) fn sky_frame(canvas: &Canvas, walls: &[Wall]) -> [Segment; 4] {
    let corner = canvas.origin + DVec2::new(canvas.width as f64, canvas.height as f64);
    let (mut lo, mut hi) = (canvas.origin.min(corner), canvas.origin.max(corner));
    for wall in walls {
        let (a, b) = wall.shape.bounds();
        if a.is_finite() && b.is_finite() {
            lo = lo.min(a);
            hi = hi.max(b);
        }
    }
    // Clear of every wall by a twentieth of the frame's size, and by at
    // least one unit, so that no wall touches the sky's lines.
    let margin = 0.05 * (hi - lo).max_element() + 1.0;
    // Within the coordinates a scene may hold: where walls reach that far,
    // the frame meets their ends there.
    let bound = DVec2::splat(flatray_tracer::scene::MAX_COORDINATE);
    let (lo, hi) = (
        (lo - margin).clamp(-bound, bound),
        (hi + margin).clamp(-bound, bound),
    );
    let (top_right, bottom_left) = (DVec2::new(hi.x, lo.y), DVec2::new(lo.x, hi.y));
    [
        Segment::new(lo, top_right),
        Segment::new(top_right, hi),
        Segment::new(hi, bottom_left),
        Segment::new(bottom_left, lo),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse_date(text: &str) -> Result<Date, String> {
        Date::try_from(text.to_string())
    }

    fn parse_time(text: &str) -> Result<TimeOfDay, String> {
        TimeOfDay::try_from(text.to_string())
    }

    fn date(text: &str) -> Date {
        parse_date(text).unwrap()
    }

    fn time(text: &str) -> TimeOfDay {
        parse_time(text).unwrap()
    }

    #[test]
    fn dates_and_times_are_read_and_checked() {
        assert_eq!(
            date("2024-02-29"),
            Date {
                year: 2024,
                month: 2,
                day: 29
            }
        );
        for bad in [
            "2026-02-29",
            "2100-02-29",
            "2026-13-01",
            "2026-04-31",
            "2026-1-01",
            "26-01-01",
            "2026/01/01",
            "0000-01-01",
            "",
        ] {
            assert!(parse_date(bad).is_err(), "{bad}");
        }
        assert_eq!(
            time("09:30"),
            TimeOfDay {
                hour: 9,
                minute: 30,
                second: 0
            }
        );
        assert_eq!(time("23:59:59").second, 59);
        for bad in [
            "24:00",
            "9:30",
            "09:60",
            "09:30:60",
            "09",
            "09:30:00:00",
            "ab:cd",
        ] {
            assert!(parse_time(bad).is_err(), "{bad}");
        }
    }

    /// The worked example of Reda and Andreas (2003), table A4.1: Golden,
    /// Colorado, 17 October 2003 at 12:30:30 local time (UTC-7), 1830.14 m,
    /// 820 mbar, 11 degrees, delta T 67 s: topocentric zenith 50.11162
    /// degrees, azimuth 194.34024 degrees.
    #[test]
    fn the_sun_stands_where_the_spa_papers_example_puts_it() {
        let place = sun_place_with(
            date("2003-10-17"),
            time("12:30:30"),
            -7.0,
            39.742476,
            -105.1786,
            Atmosphere {
                height: 1830.14,
                pressure: 820.0,
                temperature: 11.0,
                delta_t: Some(67.0),
            },
        )
        .unwrap();
        assert!(
            (90.0 - place.elevation - 50.11162).abs() < 1e-3,
            "{place:?}"
        );
        assert!((place.azimuth - 194.34024).abs() < 1e-3, "{place:?}");
    }

    /// The highest the sun climbs on a day, over every minute.
    fn highest(day: &str, zone: f64, latitude: f64, longitude: f64) -> SunPlace {
        let mut best = SunPlace {
            azimuth: 0.0,
            elevation: -90.0,
        };
        for minute in 0..24 * 60 {
            let at = TimeOfDay {
                hour: minute / 60,
                minute: minute % 60,
                second: 0,
            };
            let place = sun_place(date(day), at, zone, latitude, longitude).unwrap();
            if place.elevation > best.elevation {
                best = place;
            }
        }
        best
    }

    /// At a solstice the sun's noon elevation is 90 degrees less the
    /// latitude plus or minus the Earth's tilt (23.436 degrees in 2026),
    /// due south of a northern place and due north of a southern one
    /// beyond the tropic, lifted by refraction (Saemundsson's formula at
    /// 1010 mbar and 10 degrees: 0.05 degree at 18 degrees high). The
    /// minute-by-minute maximum is within 0.001 degree of noon's.
    #[test]
    fn the_noon_sun_of_a_solstice_stands_at_the_tilt_above_the_equator() {
        let tilt = 23.436;
        let refracted = |e: f64| {
            let arcmin = 1.02 / (e + 10.3 / (e + 5.11)).to_radians().tan();
            e + arcmin / 60.0
        };
        let near =
            |place: SunPlace, geometric: f64| (place.elevation - refracted(geometric)).abs() < 0.02;
        let paris = highest("2026-06-21", 2.0, 48.8566, 2.3522);
        assert!(near(paris, 90.0 - 48.8566 + tilt), "{paris:?}");
        assert!((paris.azimuth - 180.0).abs() < 0.5, "{paris:?}");
        let winter = highest("2026-12-21", 1.0, 48.8566, 2.3522);
        assert!(near(winter, 90.0 - 48.8566 - tilt), "{winter:?}");
        let sydney = highest("2026-12-21", 11.0, -33.8688, 151.2093);
        assert!(near(sydney, 90.0 - 33.8688 + tilt), "{sydney:?}");
        let north = sydney.azimuth.min(360.0 - sydney.azimuth);
        assert!(north < 1.0, "{sydney:?}");
    }

    #[test]
    fn the_time_zone_moves_the_clock_not_the_sun() {
        let paris = sun_place(date("2026-03-20"), time("13:00"), 1.0, 48.8566, 2.3522).unwrap();
        let utc = sun_place(date("2026-03-20"), time("12:00"), 0.0, 48.8566, 2.3522).unwrap();
        assert!((paris.azimuth - utc.azimuth).abs() < 1e-9);
        assert!((paris.elevation - utc.elevation).abs() < 1e-9);
        // Across midnight: 00:30 at UTC+2 is 22:30 UTC the day before.
        let east = sun_place(date("2026-03-21"), time("00:30"), 2.0, 10.0, 20.0).unwrap();
        let west = sun_place(date("2026-03-20"), time("22:30"), 0.0, 10.0, 20.0).unwrap();
        assert!((east.azimuth - west.azimuth).abs() < 1e-9);
        assert!(east.elevation < 0.0, "night: {east:?}");
    }

    #[test]
    fn north_turns_the_rays_on_the_canvas() {
        // North up, the sun in the south: its rays travel up the canvas.
        let d = sun_direction(180.0, 0.0);
        assert!((d - DVec2::new(0.0, -1.0)).length() < 1e-12, "{d}");
        // The sun in the east: the rays travel left (west).
        let d = sun_direction(90.0, 0.0);
        assert!((d - DVec2::new(-1.0, 0.0)).length() < 1e-12, "{d}");
        // North to the right: the south is on the left, the rays go right.
        let d = sun_direction(180.0, 90.0);
        assert!((d - DVec2::new(1.0, 0.0)).length() < 1e-12, "{d}");
    }

    #[test]
    fn the_sky_frame_encloses_the_canvas_and_every_wall_and_faces_in() {
        let canvas = Canvas {
            width: 100,
            height: 50,
            origin: DVec2::new(-10.0, 5.0),
        };
        let walls = [Wall {
            shape: flatray_geometry::Shape::Segment(Segment::new(
                DVec2::new(-200.0, 20.0),
                DVec2::new(30.0, 400.0),
            )),
            material: flatray_tracer::scene::Material::Diffuse { albedo: None },
        }];
        let frame = sky_frame(&canvas, &walls);
        let inside = [
            DVec2::new(-200.0, 20.0),
            DVec2::new(30.0, 400.0),
            DVec2::new(90.0, 55.0),
            DVec2::new(-10.0, 5.0),
        ];
        for side in &frame {
            for p in inside {
                // To the right of a -> b, with y down: cross > 0.
                assert!(side.edge().perp_dot(p - side.a) > 0.0, "{side:?} {p}");
            }
        }
        // Closed: each side starts where the one before ends.
        for k in 0..4 {
            assert_eq!(frame[k].b, frame[(k + 1) % 4].a);
        }
    }
}
