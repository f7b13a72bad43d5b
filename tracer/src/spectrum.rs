//! Light as a spectrum: the CIE 1931 colour matching functions, the
//! spectra a lamp can have (a blackbody, a gas-discharge lamp's lines, a
//! table of values), and wavelengths turned into linear sRGB.
//!
//! A spectrum `S` has the colour `M XYZ(S) / Y(S)`: its CIE 1931 tristimulus
//! values (`XYZ(S) = ∫ S(l) (x̄, ȳ, z̄)(l) dl` over 380 to 780 nm) in linear
//! sRGB (`M`, the sRGB matrix of white point D65), scaled to luminance 1,
//! as white `(1, 1, 1)` has. A colour outside sRGB's gamut (a sodium lamp's
//! yellow) keeps its negative channel: an EXR holds it, a PNG clips it.
//!
//! A path that crosses dispersive glass carries one wavelength. Its colour
//! weight `w(l) = M (x̄, ȳ, z̄)(l) / W` is linear sRGB divided, channel by
//! channel, by `W`, its mean over the range, so that an RGB light's
//! colour `c` spread over the range as `c w(l)` averages to `c`: white
//! light split by a prism and recombined is white. A lamp with a spectrum
//! sends `W S(l) Δ / Y(S)` at wavelength `l` (`Δ` = 400 nm), which `w`
//! turns back into its colour on average.
//!
//! Every spectrum is held on one grid of [`CELLS`] cells of half a
//! nanometre: its value, constant in each cell, is what is sampled and
//! what is evaluated, so that the two agree exactly.
//!
//! [`Rgb`] is the linear RGB triple every colour, albedo and light
//! quantity of the renderer is held in.

/// A linear RGB triple: a colour, an albedo, or a light quantity.
pub type Rgb = glam::DVec3;

/// The shortest and the longest wavelength counted, in nanometres.
pub const RANGE_NM: (f64, f64) = (380.0, 780.0);

/// The wavelengths a spectrum's table may give, in nm: ultraviolet to
/// infrared (what lies outside [`RANGE_NM`] is not seen, but a measured
/// lamp's table often reaches beyond it).
pub const TABLE_NM: (f64, f64) = (100.0, 10_000.0);
/// The width of the range, `Δ`.
pub const WIDTH_NM: f64 = RANGE_NM.1 - RANGE_NM.0;
/// Cells of the grid every spectrum is held on.
pub const CELLS: usize = 800;
/// A cell's width, in nanometres.
pub const CELL_NM: f64 = WIDTH_NM / CELLS as f64;
/// The standard deviation of a gas-discharge line, in nanometres: about
/// a lamp's line drawn at the grid's resolution.
pub const LINE_WIDTH_NM: f64 = 0.5;
/// The lowest and the highest blackbody temperature, in kelvin.
pub const KELVIN_RANGE: (f64, f64) = (100.0, 100_000.0);

/// The CIE 1931 2° standard observer's colour matching functions
/// `(x̄, ȳ, z̄)`, every 5 nm from 380 to 780 nm (CIE 015:2018).
#[rustfmt::skip]
const CMF: [[f64; 3]; 81] = [
    [0.001368, 3.9e-05, 0.00645],
    [0.002236, 6.4e-05, 0.01055],
    [0.004243, 0.00012, 0.02005],
    [0.00765, 0.000217, 0.03621],
    [0.01431, 0.000396, 0.06785],
    [0.02319, 0.00064, 0.1102],
    [0.04351, 0.00121, 0.2074],
    [0.07763, 0.00218, 0.3713],
    [0.13438, 0.004, 0.6456],
    [0.21477, 0.0073, 1.03905],
    [0.2839, 0.0116, 1.3856],
    [0.3285, 0.01684, 1.62296],
    [0.34828, 0.023, 1.74706],
    [0.34806, 0.0298, 1.7826],
    [0.3362, 0.038, 1.77211],
    [0.3187, 0.048, 1.7441],
    [0.2908, 0.06, 1.6692],
    [0.2511, 0.0739, 1.5281],
    [0.19536, 0.09098, 1.28764],
    [0.1421, 0.1126, 1.0419],
    [0.09564, 0.13902, 0.81295],
    [0.05795, 0.1693, 0.6162],
    [0.03201, 0.20802, 0.46518],
    [0.0147, 0.2586, 0.3533],
    [0.0049, 0.323, 0.272],
    [0.0024, 0.4073, 0.2123],
    [0.0093, 0.503, 0.1582],
    [0.0291, 0.6082, 0.1117],
    [0.06327, 0.71, 0.07825],
    [0.1096, 0.7932, 0.05725],
    [0.1655, 0.862, 0.04216],
    [0.22575, 0.91485, 0.02984],
    [0.2904, 0.954, 0.0203],
    [0.3597, 0.9803, 0.0134],
    [0.43345, 0.99495, 0.00875],
    [0.51205, 1.0, 0.00575],
    [0.5945, 0.995, 0.0039],
    [0.6784, 0.9786, 0.00275],
    [0.7621, 0.952, 0.0021],
    [0.8425, 0.9154, 0.0018],
    [0.9163, 0.87, 0.00165],
    [0.9786, 0.8163, 0.0014],
    [1.0263, 0.757, 0.0011],
    [1.0567, 0.6949, 0.001],
    [1.0622, 0.631, 0.0008],
    [1.0456, 0.5668, 0.0006],
    [1.0026, 0.503, 0.00034],
    [0.9384, 0.4412, 0.00024],
    [0.85445, 0.381, 0.00019],
    [0.7514, 0.321, 0.0001],
    [0.6424, 0.265, 5e-05],
    [0.5419, 0.217, 3e-05],
    [0.4479, 0.175, 2e-05],
    [0.3608, 0.1382, 1e-05],
    [0.2835, 0.107, -1.90582e-21],
    [0.2187, 0.0816, 0.0],
    [0.1649, 0.061, 0.0],
    [0.1212, 0.04458, 0.0],
    [0.0874, 0.032, 0.0],
    [0.0636, 0.0232, 0.0],
    [0.04677, 0.017, 0.0],
    [0.0329, 0.01192, 0.0],
    [0.0227, 0.00821, 0.0],
    [0.01584, 0.005723, 0.0],
    [0.0113592, 0.004102, 0.0],
    [0.00811092, 0.002929, 0.0],
    [0.00579035, 0.002091, 0.0],
    [0.00410946, 0.001484, 0.0],
    [0.00289933, 0.001047, 0.0],
    [0.00204919, 0.00074, 0.0],
    [0.00143997, 0.00052, 0.0],
    [0.000999949, 0.0003611, 0.0],
    [0.000690079, 0.0002492, 0.0],
    [0.000476021, 0.0001719, 0.0],
    [0.000332301, 0.00012, 0.0],
    [0.000234826, 8.48e-05, 0.0],
    [0.00016615, 6e-05, 0.0],
    [0.000117413, 4.24e-05, 0.0],
    [8.30753e-05, 3e-05, 0.0],
    [5.87065e-05, 2.12e-05, 0.0],
    [4.15099e-05, 1.499e-05, 0.0],
];

/// The CIE 1931 colour matching functions at `nm`, linear between the
/// table's wavelengths; zero outside the range.
pub fn cmf(nm: f64) -> [f64; 3] {
    let x = (nm - RANGE_NM.0) / 5.0;
    if !(0.0..=80.0).contains(&x) {
        return [0.0; 3];
    }
    let k = (x.floor() as usize).min(79);
    let f = x - k as f64;
    let (a, b) = (CMF[k], CMF[k + 1]);
    [
        a[0] + (b[0] - a[0]) * f,
        a[1] + (b[1] - a[1]) * f,
        a[2] + (b[2] - a[2]) * f,
    ]
}

/// CIE XYZ to linear sRGB (IEC 61966-2-1, white point D65).
pub fn xyz_to_rgb([x, y, z]: [f64; 3]) -> Rgb {
    Rgb::new(
        3.240_454_2 * x - 1.537_138_5 * y - 0.498_531_4 * z,
        -0.969_266_0 * x + 1.876_010_8 * y + 0.041_556_0 * z,
        0.055_643_4 * x - 0.204_025_9 * y + 1.057_225_2 * z,
    )
}

/// The chromaticity `(x, y)` of tristimulus values.
pub fn chromaticity([x, y, z]: [f64; 3]) -> (f64, f64) {
    let sum = x + y + z;
    (x / sum, y / sum)
}

/// `W`: the mean of `M (x̄, ȳ, z̄)` over the range, exactly (the functions
/// are linear between the table's wavelengths: the trapezoid rule).
fn balance() -> Rgb {
    use std::sync::OnceLock;
    static W: OnceLock<Rgb> = OnceLock::new();
    *W.get_or_init(|| {
        let mut sum = [0.0; 3];
        for (k, row) in CMF.iter().enumerate() {
            let weight = if k == 0 || k == 80 { 0.5 } else { 1.0 };
            for c in 0..3 {
                sum[c] += weight * row[c] * 5.0;
            }
        }
        xyz_to_rgb(sum) / WIDTH_NM
    })
}

/// The colour weight of wavelength `nm` for a path that drew it uniformly
/// from the range: `M (x̄, ȳ, z̄)(nm) / W`, of mean exactly `(1, 1, 1)`
/// over the range.
pub fn wavelength_rgb(nm: f64) -> Rgb {
    xyz_to_rgb(cmf(nm)) / balance()
}

/// A named gas-discharge lamp.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lamp {
    Sodium,
    Mercury,
    Neon,
    Hydrogen,
}

impl Lamp {
    /// The lamp's visible lines: wavelength in air (nm) and relative
    /// intensity, after the NIST Atomic Spectra Database's tables of
    /// strong lines (the intensities are rounded; a real lamp's vary with
    /// its pressure and current).
    pub fn lines(self) -> &'static [(f64, f64)] {
        match self {
            Lamp::Sodium => &[
                (588.995, 1000.0),
                (589.592, 500.0),
                (568.263, 3.5),
                (568.820, 7.0),
                (615.423, 2.2),
                (616.075, 4.5),
                (498.281, 0.4),
            ],
            Lamp::Mercury => &[
                (404.656, 1800.0),
                (407.783, 150.0),
                (435.833, 4000.0),
                (491.604, 80.0),
                (546.074, 1100.0),
                (576.960, 240.0),
                (579.066, 280.0),
            ],
            Lamp::Neon => &[
                (540.056, 6000.0),
                (585.249, 20000.0),
                (588.190, 10000.0),
                (594.483, 5000.0),
                (597.553, 6000.0),
                (603.000, 10000.0),
                (607.434, 10000.0),
                (609.616, 30000.0),
                (614.306, 10000.0),
                (616.359, 10000.0),
                (621.728, 10000.0),
                (626.650, 10000.0),
                (630.479, 10000.0),
                (633.443, 10000.0),
                (638.299, 10000.0),
                (640.225, 20000.0),
                (650.653, 15000.0),
                (653.288, 10000.0),
                (659.895, 10000.0),
                (667.828, 5000.0),
                (671.704, 7000.0),
                (692.947, 100000.0),
                (703.241, 85000.0),
                (717.394, 10000.0),
                (724.517, 10000.0),
            ],
            Lamp::Hydrogen => &[
                (397.007, 8.0),
                (410.174, 15.0),
                (434.047, 30.0),
                (486.133, 80.0),
                (656.285, 300.0),
            ],
        }
    }

    /// The lamp's name in the scene format.
    pub fn name(self) -> &'static str {
        match self {
            Lamp::Sodium => "Sodium",
            Lamp::Mercury => "Mercury",
            Lamp::Neon => "Neon",
            Lamp::Hydrogen => "Hydrogen",
        }
    }
}

/// Values every 5 nm from 380 to 780 nm, linear between: a table of a
/// spectrum given as pairs, resampled (`Spectrum::table`).
pub const TABLE_POINTS: usize = 81;

/// What a lamp emits, wavelength by wavelength, up to a factor: its
/// intensity sets the scale, and the spectrum its colour.
///
/// A table is held inline (324 bytes) so that a `Light` stays `Copy`;
/// the render reads a light's spectrum only from the scene's sampled
/// copies, never by moving a `Light`.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Spectrum {
    /// Planck's law at a temperature in kelvin.
    Blackbody { kelvin: f64 },
    /// A gas-discharge lamp's lines, each a narrow Gaussian.
    Lamp(Lamp),
    /// Values every 5 nm from 380 to 780 nm, linear between.
    Table([f32; TABLE_POINTS]),
}

/// Why a table of (wavelength, value) pairs is no spectrum.
pub type TableError = String;

impl Spectrum {
    /// A spectrum from (wavelength in nm, value) pairs in increasing order of
    /// wavelength, linear between them and zero outside them, resampled
    /// every 5 nm: it needs two pairs or more, wavelengths within
    /// [`TABLE_NM`], finite values of at least 0, and some light within
    /// 380 to 780 nm. Only the values' ratios count (a spectrum sets a
    /// colour, not a brightness), so values of any size are taken.
    pub fn table(pairs: &[(f64, f64)]) -> Result<Spectrum, TableError> {
        if pairs.len() < 2 {
            return Err(format!(
                "a spectrum's table needs at least 2 (wavelength, value) pairs, found {}",
                pairs.len()
            ));
        }
        for (k, &(nm, v)) in pairs.iter().enumerate() {
            if !(nm.is_finite() && v.is_finite() && v >= 0.0) {
                return Err(format!(
                    "a spectrum's pair {k} is ({nm}, {v}): expected a finite wavelength in nm and a value of at least 0"
                ));
            }
            if !(TABLE_NM.0..=TABLE_NM.1).contains(&nm) {
                return Err(format!(
                    "a spectrum's pair {k} is at {nm} nm: wavelengths are from {} to {} nm (ultraviolet to infrared; 380 to 780 nm is what is seen)",
                    TABLE_NM.0, TABLE_NM.1
                ));
            }
            if k > 0 && nm <= pairs[k - 1].0 {
                return Err(format!(
                    "a spectrum's wavelengths must increase: pair {k} ({nm} nm) follows {} nm",
                    pairs[k - 1].0
                ));
            }
        }
        // Values far outside f32's range are brought into it first: the
        // same ratios, none lost to infinity or zero.
        let largest = pairs.iter().map(|p| p.1).fold(0.0, f64::max);
        let scale = if largest > 1e30 || (largest > 0.0 && largest < 1e-30) {
            1.0 / largest
        } else {
            1.0
        };
        let at = |nm: f64| {
            let k = pairs.partition_point(|p| p.0 <= nm);
            if k == 0 || k == pairs.len() && nm > pairs[k - 1].0 {
                return 0.0;
            }
            if k == pairs.len() {
                return pairs[k - 1].1;
            }
            let (a, b) = (pairs[k - 1], pairs[k]);
            a.1 + (b.1 - a.1) * ((nm - a.0) / (b.0 - a.0))
        };
        let values: [f32; TABLE_POINTS] =
            std::array::from_fn(|k| (at(RANGE_NM.0 + 5.0 * k as f64) * scale) as f32);
        if values.iter().all(|&v| v == 0.0) || values.iter().any(|v| !v.is_finite()) {
            return Err("a spectrum's table gives no light from 380 to 780 nm".into());
        }
        Ok(Spectrum::Table(values))
    }

    /// Bits that tell spectra apart: equal for equal spectra.
    pub fn key(&self) -> Vec<u64> {
        match *self {
            Spectrum::Blackbody { kelvin } => vec![0, kelvin.to_bits()],
            Spectrum::Lamp(lamp) => vec![1, lamp as u64],
            Spectrum::Table(values) => std::iter::once(2)
                .chain(values.iter().map(|v| v.to_bits() as u64))
                .collect(),
        }
    }

    /// Its relative value at `nm`.
    pub fn value(&self, nm: f64) -> f64 {
        match *self {
            Spectrum::Blackbody { kelvin } => planck(nm, kelvin),
            Spectrum::Lamp(lamp) => {
                let s = LINE_WIDTH_NM;
                lamp.lines()
                    .iter()
                    .map(|&(centre, i)| {
                        let d = (nm - centre) / s;
                        i * (-0.5 * d * d).exp() / (s * std::f64::consts::TAU.sqrt())
                    })
                    .sum()
            }
            Spectrum::Table(values) => {
                let x = (nm - RANGE_NM.0) / 5.0;
                if !(0.0..=80.0).contains(&x) {
                    return 0.0;
                }
                let k = (x.floor() as usize).min(TABLE_POINTS - 2);
                let f = x - k as f64;
                let (a, b) = (values[k] as f64, values[k + 1] as f64);
                a + (b - a) * f
            }
        }
    }

    /// The spectrum on the grid of cells, each cell's value at its centre.
    pub fn sampled(&self) -> Sampled {
        let values: Vec<f64> = (0..CELLS)
            .map(|c| self.value(RANGE_NM.0 + (c as f64 + 0.5) * CELL_NM).max(0.0))
            .collect();
        Sampled::new(values)
    }
}

/// Planck's law, up to a factor: `l^-5 / (exp(c2 / (l T)) - 1)`, `l` in
/// metres.
fn planck(nm: f64, kelvin: f64) -> f64 {
    const C2: f64 = 1.438_776_877e-2;
    let l = nm * 1e-9;
    let x = C2 / (l * kelvin);
    // Scaled by 1e-30 (l^5 is about 1e-32): the same factor for every
    // wavelength, so a ratio of values is unchanged.
    1e-30 / (l.powi(5) * x.exp_m1())
}

/// A spectrum held on the grid: its value in each cell, normalised to
/// luminance 1 (`∫ S ȳ = 1`), with the cumulative sums that draw a
/// wavelength in proportion to it.
#[derive(Clone, Debug, PartialEq)]
pub struct Sampled {
    values: Vec<f64>,
    cumulative: Vec<f64>,
    /// `∫ S` over the range, after the normalisation.
    total: f64,
    /// Its colour, `M XYZ(S)`: luminance 1.
    rgb: Rgb,
    xyz: [f64; 3],
}

impl Sampled {
    fn new(mut values: Vec<f64>) -> Sampled {
        // Each cell's XYZ is its value times the integral of the linear
        // colour matching functions over it: their value at its centre
        // (the cells divide the table's 5 nm steps).
        let mut xyz = [0.0; 3];
        for (c, &v) in values.iter().enumerate() {
            let m = cmf(RANGE_NM.0 + (c as f64 + 0.5) * CELL_NM);
            for k in 0..3 {
                xyz[k] += v * m[k] * CELL_NM;
            }
        }
        let y = if xyz[1] > 0.0 && xyz[1].is_finite() {
            xyz[1]
        } else {
            1.0
        };
        for v in &mut values {
            *v /= y;
        }
        let xyz = xyz.map(|t| t / y);
        let mut sum = 0.0;
        let cumulative = values
            .iter()
            .map(|&v| {
                sum += v * CELL_NM;
                sum
            })
            .collect();
        Sampled {
            values,
            cumulative,
            total: sum,
            rgb: xyz_to_rgb(xyz),
            xyz,
        }
    }

    /// The colour, luminance 1: what the lamp is where no glass disperses.
    pub fn rgb(&self) -> Rgb {
        self.rgb
    }

    /// Its tristimulus values, `Y` = 1.
    pub fn xyz(&self) -> [f64; 3] {
        self.xyz
    }

    /// Its value at `nm` (luminance 1): constant in each cell.
    pub fn value(&self, nm: f64) -> f64 {
        let c = (nm - RANGE_NM.0) / CELL_NM;
        if !(0.0..CELLS as f64).contains(&c) {
            return 0.0;
        }
        self.values[c as usize]
    }

    /// A wavelength drawn in proportion to the spectrum with `u` in
    /// `[0, 1)`, and its density per nanometre.
    pub fn sample(&self, u: f64) -> (f64, f64) {
        let target = u * self.total;
        let c = self
            .cumulative
            .partition_point(|&s| s <= target)
            .min(CELLS - 1);
        let before = if c == 0 { 0.0 } else { self.cumulative[c - 1] };
        let within = if self.values[c] > 0.0 {
            ((target - before) / (self.values[c] * CELL_NM)).clamp(0.0, 1.0)
        } else {
            0.5
        };
        let nm = RANGE_NM.0 + (c as f64 + within) * CELL_NM;
        (nm, self.values[c] / self.total)
    }

    /// What a lamp of this spectrum sends at `nm` to a path that carries
    /// that wavelength: `W S(nm) Δ`, which the path's weight `w` turns
    /// into the colour on average.
    pub fn at_wavelength(&self, nm: f64) -> Rgb {
        balance() * (self.value(nm) * WIDTH_NM)
    }

    /// The colour of a photon of this spectrum that carries wavelength
    /// `nm`, drawn by [`Sampled::sample`]: `M (x̄, ȳ, z̄)(nm) ∫ S`, which
    /// averages to the colour.
    pub fn photon_rgb(&self, nm: f64) -> Rgb {
        xyz_to_rgb(cmf(nm)) * self.total
    }
}

/// How paths draw a wavelength at their first dispersive edge: half
/// uniformly over the range, half in proportion to the scene's lamps'
/// spectra (each alike), so that a lamp's narrow lines are found. A scene
/// without a lamp of a spectrum draws uniformly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mixture<'a> {
    spectra: &'a [Sampled],
}

impl<'a> Mixture<'a> {
    pub fn new(spectra: &'a [Sampled]) -> Mixture<'a> {
        Mixture { spectra }
    }

    /// A wavelength in nm and its density per nm, from two numbers in
    /// `[0, 1)`.
    pub fn sample(&self, u: f64, v: f64) -> (f64, f64) {
        let n = self.spectra.len();
        let nm = if n == 0 || u < 0.5 {
            RANGE_NM.0 + WIDTH_NM * v
        } else {
            let k = (((u - 0.5) * 2.0 * n as f64) as usize).min(n - 1);
            self.spectra[k].sample(v).0
        };
        (nm, self.pdf(nm))
    }

    /// The density per nm of [`Mixture::sample`] at `nm`.
    pub fn pdf(&self, nm: f64) -> f64 {
        let n = self.spectra.len();
        if n == 0 {
            return 1.0 / WIDTH_NM;
        }
        let lamps: f64 = self
            .spectra
            .iter()
            .map(|s| s.value(nm) / s.total)
            .sum::<f64>()
            / n as f64;
        0.5 / WIDTH_NM + 0.5 * lamps
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_table_is_checked_and_only_its_ratios_count() {
        for (bad, says) in [
            (vec![(-400.0, 1.0), (0.0, 1.0), (500.0, 1.0)], "-400 nm"),
            (vec![(0.0, 1.0), (500.0, 1.0)], "0 nm"),
            (vec![(500.0, 1.0), (2e4, 1.0)], "20000 nm"),
            (vec![(500.0, 1.0), (400.0, 1.0)], "must increase"),
            (vec![(500.0, 1.0), (500.0, 1.0)], "must increase"),
            (vec![(400.0, -1.0), (500.0, 1.0)], "at least 0"),
            (vec![(400.0, f64::NAN), (500.0, 1.0)], "finite"),
            (vec![(400.0, f64::INFINITY), (500.0, 1.0)], "finite"),
            (vec![(400.0, 0.0), (500.0, 0.0)], "no light"),
            (vec![(100.0, 1.0), (300.0, 1.0)], "no light"),
            (vec![(500.0, 1.0)], "at least 2"),
        ] {
            let why = Spectrum::table(&bad).expect_err("refused");
            assert!(why.contains(says), "{bad:?}: {why}");
        }
        let colour = |v: f64| {
            Spectrum::table(&[(400.0, 0.5 * v), (550.0, v), (700.0, 0.25 * v)])
                .expect("a table")
                .sampled()
                .rgb()
        };
        let unit = colour(1.0);
        for v in [1e308, 1e-300, 1e20] {
            let c = colour(v);
            for k in 0..3 {
                assert!((c[k] - unit[k]).abs() < 1e-5, "{v}: {c:?} vs {unit:?}");
            }
        }
    }

    /// The blackbody's chromaticity against the CIE 1931 Planckian locus
    /// (CIE 015:2018's observer, 1 nm sums from 360 to 830 nm), within
    /// 0.002 in x and y.
    #[test]
    fn a_blackbody_has_the_planckian_locus_chromaticity() {
        for (kelvin, x, y) in [
            (2000.0, 0.5267, 0.4133),
            (4000.0, 0.3804, 0.3767),
            (6504.0, 0.3135, 0.3236),
            (10000.0, 0.2806, 0.2883),
        ] {
            let s = Spectrum::Blackbody { kelvin }.sampled();
            let (cx, cy) = chromaticity(s.xyz());
            assert!(
                (cx - x).abs() < 0.002 && (cy - y).abs() < 0.002,
                "{kelvin} K: ({cx:.4}, {cy:.4}), expected ({x}, {y})"
            );
        }
    }

    /// A blackbody at 6504 K is white in sRGB to within 5 % per channel
    /// (sRGB's white is D65, whose chromaticity lies 0.005 from the
    /// Planckian locus: the blackbody is (1.043, 0.984, 1.035), a touch
    /// of magenta), and its luminance is 1.
    #[test]
    fn a_blackbody_at_6504_kelvin_is_white() {
        let rgb = Spectrum::Blackbody { kelvin: 6504.0 }.sampled().rgb();
        assert!((rgb - Rgb::ONE).abs().max_element() < 0.05, "{rgb}");
        let y = 0.2126 * rgb.x + 0.7152 * rgb.y + 0.0722 * rgb.z;
        assert!((y - 1.0).abs() < 1e-3, "{y}");
    }

    /// Wavelength weights average to white over the range, and a
    /// spectrum's wavelengths, weighed as a path or a photon weighs them,
    /// average to its colour.
    #[test]
    fn wavelengths_average_to_the_colour() {
        let n = 40_000;
        let mut sum = Rgb::ZERO;
        for k in 0..n {
            sum += wavelength_rgb(RANGE_NM.0 + WIDTH_NM * (k as f64 + 0.5) / n as f64);
        }
        assert!((sum / n as f64 - Rgb::ONE).abs().max_element() < 1e-6);
        for spectrum in [
            Spectrum::Blackbody { kelvin: 3000.0 },
            Spectrum::Lamp(Lamp::Sodium),
            Spectrum::Lamp(Lamp::Neon),
            Spectrum::table(&[(450.0, 1.0), (500.0, 0.2), (650.0, 0.7)]).expect("a table"),
        ] {
            let s = spectrum.sampled();
            // A path: uniform wavelengths, the lamp's value times the weight.
            let mut path = Rgb::ZERO;
            // A photon: wavelengths drawn by the spectrum (stratified).
            let mut photon = Rgb::ZERO;
            for k in 0..n {
                let u = (k as f64 + 0.5) / n as f64;
                let nm = RANGE_NM.0 + WIDTH_NM * u;
                path += s.at_wavelength(nm) * wavelength_rgb(nm);
                photon += s.photon_rgb(s.sample(u).0);
            }
            let (path, photon) = (path / n as f64, photon / n as f64);
            assert!(
                (path - s.rgb()).abs().max_element() < 2e-3,
                "{spectrum:?}: {path} {}",
                s.rgb()
            );
            assert!(
                (photon - s.rgb()).abs().max_element() < 2e-3,
                "{spectrum:?}: {photon} {}",
                s.rgb()
            );
        }
    }

    /// The mixture's density integrates to 1 and its draws follow it.
    #[test]
    fn the_mixture_draws_its_density() {
        let mercury = [Spectrum::Lamp(Lamp::Mercury).sampled()];
        let m = Mixture::new(&mercury);
        let integral: f64 = (0..CELLS)
            .map(|c| m.pdf(RANGE_NM.0 + (c as f64 + 0.5) * CELL_NM) * CELL_NM)
            .sum();
        assert!((integral - 1.0).abs() < 1e-9, "{integral}");
        // The share of draws within a nanometre of the 435.8 nm line.
        let near = |nm: f64| (nm - 435.833).abs() < 1.0;
        let expected: f64 = (0..CELLS)
            .map(|c| RANGE_NM.0 + (c as f64 + 0.5) * CELL_NM)
            .filter(|&nm| near(nm))
            .map(|nm| m.pdf(nm) * CELL_NM)
            .sum();
        let n = 100_000;
        let mut state = 7u64;
        let mut uniform = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let hits = (0..n)
            .filter(|_| near(m.sample(uniform(), uniform()).0))
            .count() as f64;
        let se = (n as f64 * expected * (1.0 - expected)).sqrt();
        assert!(
            (hits - n as f64 * expected).abs() < 5.0 * se,
            "{hits} against {}",
            n as f64 * expected
        );
    }
}
