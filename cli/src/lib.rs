//! The flatray command line: flag definitions and the glue that loads a
//! scene, renders it and writes the result.
//!
//! What it is for: parsing arguments, showing progress, printing summaries
//! and statistics, and owning the exit codes (0 success, 2 bad usage or a
//! bad scene, 1 any other failure).
//!
//! What it never does: physics or file formats. Those live in
//! `flatray-tracer` and `flatray-io`; this crate only wires them together,
//! and never panics on user input.

use std::ffi::OsString;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::{Parser, Subcommand, ValueEnum};
use flatray_io::{Format, Loaded};
use flatray_tracer::{FastPath, FastPaths, Integrator, LightChoice, MemoOptions, RenderOptions};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Exit code: success.
pub const EXIT_OK: i32 = 0;
/// Exit code: any failure that is not the user's input.
pub const EXIT_FAILURE: i32 = 1;
/// Exit code: bad usage or a bad scene.
pub const EXIT_USAGE: i32 = 2;

/// What `flatray --help` says first.
const LONG_ABOUT: &str = "\
Lights a floor plan seen from above: walls (diffuse, mirror, transparent), \
glass and lamps, with shadows, light bounced off walls and their colour, \
mirrors and caustics. flatray writes a tone-mapped PNG or a linear EXR.

Examples:
  flatray render scenes/room.ron -o room.png            render the example room
  flatray render scenes/room.ron --scale 0.25 --spp 8   a quick preview
  flatray plan scenes/room.ron                          which effects the scene calls for
  flatray import plan.svg -o plan.ron                   a plan from Inkscape, Tiled or a mask

Scene files: docs/scene-format.md. The physics: docs/model.md.";

/// flatray: a 2D path tracer for floor plans.
#[derive(Debug, Parser)]
#[command(
    name = "flatray",
    version,
    about = "Lights a floor plan: a 2D path tracer for walls, mirrors, glass and lamps seen from above",
    long_about = LONG_ABOUT
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Render a scene to a PNG (tone-mapped) or EXR (linear) image.
    #[command(after_help = "Examples:
  flatray render scenes/room.ron -o room.png                render with the scene's settings
  flatray render scenes/room.ron --scale 0.25 --spp 8       a quick preview
  flatray render scenes/room.ron --target-error 1 -o r.exr  until the noise is about 1 % relMSE
  flatray render scenes/room.ron --stats --json             what was done, for a script")]
    Render(RenderArgs),
    /// Validate scene files and warn about what would make a render wrong
    /// or wasteful; exit 0, or print the errors and exit 2.
    #[command(after_help = "Examples:
  flatray check scenes/room.ron                 ok, or the error with its line and column
  flatray check scenes/*.ron                    every scene in a folder
  flatray check plan.ron --json                 one JSON object (docs/cli.md)")]
    Check {
        /// The scene files (RON).
        #[arg(required = true)]
        scenes: Vec<PathBuf>,
        /// Print one JSON object instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Print the render plan: which effects the scene calls for, which are
    /// skipped and why.
    #[command(after_help = "Examples:
  flatray plan scenes/room.ron                  the effects simulated and skipped
  flatray plan scenes/room.ron --bounces 3      the same with more bounces
  flatray plan scenes/room.ron --verbose        how the work is done too
  flatray plan scenes/room.ron --json           one JSON object (docs/cli.md)")]
    Plan {
        /// The scene file (RON).
        scene: PathBuf,
        /// Most diffuse reflections off walls (overrides the scene; default
        /// 1).
        #[arg(long, value_parser = clap::value_parser!(u32).range(0..=1000))]
        bounces: Option<u32>,
        /// Most mirror and glass events in a row (overrides the scene;
        /// default 32).
        #[arg(long, value_parser = clap::value_parser!(u32).range(0..=1000))]
        specular: Option<u32>,
        /// The cache of light on walls (overrides the scene; default on).
        #[arg(long, value_enum)]
        cache: Option<CacheArg>,
        /// The caustic pass: points, spots and sun seen in mirrors and
        /// glass (overrides the scene; default on).
        #[arg(long, value_enum)]
        caustics: Option<Switch>,
        /// Which lights each point's shadow rays go to (overrides the
        /// scene; default: auto).
        #[arg(long, value_enum)]
        lights: Option<LightsArg>,
        /// The estimator (overrides the scene; default path).
        #[arg(long, value_enum)]
        integrator: Option<IntegratorArg>,
        /// Also say how the work is done (shared shadow rays, culling,
        /// the kind of ray queries).
        #[arg(long, short)]
        verbose: bool,
        /// Print one JSON object instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Show a scene's render converge in a browser page, and edit it there:
    /// drag lights and walls, change intensities, colours and materials,
    /// undo, save.
    #[command(after_help = "Examples:
  flatray serve scenes/room.ron              then open http://127.0.0.1:8421/
  flatray serve plan.ron --port 0 --open     any free port, opened in the browser
  flatray serve plan.ron --host 0.0.0.0      other machines too (they can edit and save)

The page: docs/serve.md.")]
    Serve(serve::ServeArgs),
    /// Measure error against seconds and samples for each way of rendering.
    #[command(after_help = "Examples:
  flatray converge scenes/room.ron --scale 0.5                 every way of rendering, a reference first
  flatray converge scenes/room.ron --configs path-cache,light  two of them
  flatray converge scenes/room.ron --reference ref.exr         against a reference of your own")]
    Converge(converge::ConvergeArgs),
    /// Render a day: a frame every so often, every `Sun` of the scene at
    /// that frame's time, written as an animated PNG.
    #[command(after_help = "Examples:
  flatray day scenes/daylight.ron --from 08:00 --to 16:00 --every 1h -o day.png
  flatray day plan.ron --date 2026-06-21 --from 05:00 --to 21:00 --every 30m --spp 8 --scale 0.5")]
    Day(day::DayArgs),
    /// Measure each room's illuminance: E_min, E_avg, E_max and U0 on the
    /// EN 12464-1 grid, the daylight factor under a sky, each with its
    /// standard error.
    #[command(after_help = "Examples:
  flatray measure scenes/flat.ron                            a table of the rooms' figures
  flatray measure plan.ron --map map.png --csv grid.csv      the false-colour map and the grid
  flatray measure plan.ron --json --spp 256 --batches 16     for scripts, more samples

The figures and how to read them: docs/daylight.md.")]
    Measure(measure::MeasureArgs),
    /// Turn a floor plan from another tool (an SVG drawing, a Tiled map in
    /// TMX or JSON, a Universal VTT map, a wall-mask image) into a
    /// commented scene file.
    #[command(after_help = "Examples:
  flatray import plan.svg -o plan.ron                 an Inkscape drawing (docs/import.md)
  flatray import plan.svg --scale 0.5 -o plan.ron     half size: 2 SVG units to a canvas pixel
  flatray import level.tmx -o level.ron               a Tiled map
  flatray import tavern.dd2vtt --doors open           a Dungeondraft map, its image the floor
  flatray import walls.png --tolerance 2 -o w.ron     a wall mask, outlines simplified")]
    Import(ImportArgs),
    /// Make up an apartment's floor plan (rooms with doors and windows,
    /// furniture, coloured walls, mirrors, lamps) as a scene file: for
    /// trying flatray, and benchmarking it, on a plan of any size.
    #[command(after_help = "Examples:
  flatray generate -o apartment.ron                     16 rooms
  flatray generate --rooms 400 --lamps 2 -o big.ron     a large plan, for benchmarks
  flatray generate --seed 7 --no-sun -o night.ron       another plan, at night")]
    Generate(GenerateArgs),
    /// Print a shell completion script (for example:
    /// `flatray completions bash > ~/.local/share/bash-completion/completions/flatray`).
    #[command(after_help = "Examples:
  flatray completions bash > ~/.local/share/bash-completion/completions/flatray
  flatray completions zsh > ~/.zfunc/_flatray")]
    Completions {
        /// The shell.
        shell: clap_complete::Shell,
    },
    /// Print a manual page in roff (for example: `flatray man | man -l -`).
    #[command(after_help = "Examples:
  flatray man | man -l -                 the page of flatray(1)
  flatray man render | man -l -          the page of flatray-render(1)
  flatray man render > flatray-render.1  to install")]
    Man {
        /// The subcommand whose page to print (default: flatray's own).
        subcommand: Option<String>,
    },
}

#[derive(Debug, clap::Args)]
struct ImportArgs {
    /// The plan: .svg, .tmx, .json/.tmj, .dd2vtt/.uvtt/.df2vtt or a mask
    /// image (.png).
    plan: PathBuf,
    /// The scene file to write. Default: the plan's name with .ron, in the
    /// current folder.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Canvas pixels per unit of the plan: an SVG user unit of 1/96 inch,
    /// a Tiled or mask pixel (default 1), a Universal VTT grid cell
    /// (default the map's pixels_per_grid).
    #[arg(long, allow_negative_numbers = true)]
    scale: Option<f64>,
    /// Curves are flattened, mask outlines simplified, and windows and
    /// doors matched to their walls, to within this distance in the plan's
    /// units (a Universal VTT map's: pixels of its image).
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    tolerance: f64,
    /// A Universal VTT map's doors: as the map draws them, all open, or
    /// all shut.
    #[arg(long, value_enum, default_value_t = DoorsArg::AsDrawn)]
    doors: DoorsArg,
    /// What a Universal VTT portal that lets light through is (Dungeondraft
    /// writes its windows so).
    #[arg(long, value_enum, default_value_t = OpenPortalsArg::Windows)]
    open_portals: OpenPortalsArg,
    /// A Universal VTT map's lights: kept as lamps, or none.
    #[arg(long, value_enum, default_value_t = MapLightsArg::Keep)]
    lights: MapLightsArg,
    /// The Tiled object layer whose objects become walls.
    #[arg(long, default_value = "walls")]
    walls_layer: String,
    /// The Tiled object layer whose objects become lights.
    #[arg(long, default_value = "lights")]
    lights_layer: String,
    /// Use the SVG's first bitmap as the floor (written beside the scene).
    #[arg(long)]
    floor_image: bool,
    /// Replace the scene file (and floor image) if it exists.
    #[arg(long)]
    force: bool,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub(crate) enum ErrorMetricArg {
    Relmse,
    Rms,
}

impl ErrorMetricArg {
    pub(crate) fn metric(self) -> flatray_tracer::metrics::ErrorMetric {
        match self {
            ErrorMetricArg::Relmse => flatray_tracer::metrics::ErrorMetric::RelMse,
            ErrorMetricArg::Rms => flatray_tracer::metrics::ErrorMetric::Rms,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum DoorsArg {
    AsDrawn,
    Open,
    Closed,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum OpenPortalsArg {
    Windows,
    Doors,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum MapLightsArg {
    Keep,
    None,
}

#[derive(Debug, clap::Args)]
struct GenerateArgs {
    /// The scene file to write.
    #[arg(short, long, default_value = "apartment.ron")]
    output: PathBuf,
    /// Rooms, on a grid about as wide as it is tall.
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=10_000))]
    rooms: u32,
    /// Lamps per room: points, and from 4 lamps a room on, every fourth
    /// of a room's lamps a spot (so 1 to 3 make points only).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(0..=64))]
    lamps: u32,
    /// The share of rooms with a mirror, 0 to 1.
    #[arg(long, default_value_t = 0.3, allow_negative_numbers = true)]
    mirrors: f64,
    /// No sunlight through the windows.
    #[arg(long)]
    no_sun: bool,
    /// Which plan of this size: the same seed makes the same plan.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Replace the scene file if it exists.
    #[arg(long)]
    force: bool,
}

#[derive(Debug, clap::Args)]
#[command(group(clap::ArgGroup::new("passes").args(["target_error", "time"]).multiple(true)))]
struct RenderArgs {
    /// The scene file (RON).
    scene: PathBuf,
    /// The output image; its extension (.png or .exr) picks the format.
    /// Default: the scene's name with .png, in the current folder.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Samples per pixel (overrides the scene's `samples`; default 16).
    #[arg(long, visible_alias = "samples", value_parser = clap::value_parser!(u32).range(1..=(1 << 20)), conflicts_with_all = ["target_error", "time"])]
    spp: Option<u32>,
    /// Most diffuse reflections off walls between a light and the floor
    /// (overrides the scene; default 1). Mirrors, glass and panes do not
    /// count.
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=1000))]
    bounces: Option<u32>,
    /// Most mirror and glass events in a row, between a light, a wall or
    /// the floor and the next (overrides the scene; default 32, with
    /// Russian roulette past 8).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=1000))]
    specular: Option<u32>,
    /// Seed of the random streams (overrides the scene; default 0).
    #[arg(long)]
    seed: Option<u64>,
    /// Multiplies every pixel value (overrides the scene; default 1).
    #[arg(long, allow_negative_numbers = true)]
    exposure: Option<f64>,
    /// The estimator (overrides the scene; default path).
    #[arg(long, value_enum)]
    integrator: Option<IntegratorArg>,
    /// The cache of light on walls (overrides the scene; default on).
    #[arg(long, value_enum)]
    cache: Option<CacheArg>,
    /// The caustic pass: points, spots and sun seen in mirrors and glass
    /// (overrides the scene; default on; off, their light through mirrors
    /// and glass is missing).
    #[arg(long, value_enum)]
    caustics: Option<Switch>,
    /// Which lights each point's shadow rays go to (overrides the scene;
    /// default: auto).
    #[arg(long, value_enum)]
    lights: Option<LightsArg>,
    /// Render the canvas at this many pixels per world unit (0.25 for a
    /// preview, 2 for a sharper image); the geometry is unchanged.
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    scale: f64,
    /// Worker threads (default: one per core).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1024))]
    threads: Option<u32>,
    /// Print counts of rays, paths and seconds per phase.
    #[arg(long)]
    stats: bool,
    /// Render until the estimated noise (by --error-metric: relMSE, each
    /// pixel's error relative to its own value) is at most this many
    /// percent, in passes that add samples to the image (16 spp, then
    /// doubling). The image is exactly the single render with the
    /// samples reached.
    #[arg(long, value_name = "PERCENT", allow_negative_numbers = true)]
    target_error: Option<f64>,
    /// The error --target-error aims at: relmse (the root of relMSE, each
    /// pixel's error over its own value, dark regions counting as bright
    /// ones) or rms (the image's RMS error over its RMS value).
    #[arg(long, value_enum, default_value_t = ErrorMetricArg::Relmse)]
    error_metric: ErrorMetricArg,
    /// Render with as many samples as fit in this many seconds, in passes
    /// that add samples to the image (with --target-error: stop at
    /// whichever comes first). At least the first pass is taken.
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    time: Option<f64>,
    /// With --target-error or --time: write the image after each pass, so
    /// that a long render can be looked at as it goes.
    #[arg(long, requires = "passes")]
    write_passes: bool,
    /// Adaptive passes: from the third pass (32 spp) on, each pass adds
    /// samples only where a pixel's estimated noise, averaged with its
    /// neighbours', is at least a quarter of the image's mean
    /// (docs/model.md, "Adaptive passes"). --spp is then the most any
    /// pixel takes.
    #[arg(long)]
    adaptive: bool,
    /// How the floor's indirect light is gathered: along lines across the
    /// image (default, where the plan allows; docs/model.md, "Lines
    /// across the floor"), or by each pixel's own path samples.
    #[arg(long, value_enum, value_name = "HOW")]
    indirect: Option<IndirectArg>,
    /// Write a picture of the samples each pixel took to this PNG file:
    /// grey in proportion, white the most.
    #[arg(long, value_name = "PNG")]
    write_spp: Option<PathBuf>,
    /// Print the statistics as --stats does, and also how the work was
    /// done (the full plan, culling, cache hits, shared shadow rays).
    #[arg(long, short)]
    verbose: bool,
    /// Print one JSON object (what was written, the plan, the
    /// statistics and the seconds) instead of text: docs/cli.md.
    #[arg(long)]
    json: bool,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
    /// Draw the walls over the image (PNG only), each material in its own
    /// colour: diffuse walls in theirs, mirrors silver-blue, panes in
    /// their tint, glass pale cyan, emitting walls yellow.
    #[arg(long)]
    draw_walls: bool,
    /// Render again each time the scene file (or its floor image) is
    /// saved, until interrupted; a scene that does not load is reported
    /// and waited on.
    #[arg(long, conflicts_with = "json")]
    watch: bool,
    /// Debugging and benchmarking: render with the plain model, every
    /// effect on and no fast path (the same image, more slowly).
    #[arg(long, hide = true)]
    reference: bool,
    /// Benchmarking: leave out these fast paths (comma-separated), each of
    /// which computes the same image as the model (the same bits).
    #[arg(long, hide = true, value_enum, value_delimiter = ',')]
    without: Vec<FastPathArg>,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum Switch {
    On,
    Off,
}

impl Switch {
    fn on(self) -> bool {
        matches!(self, Switch::On)
    }
}

/// How the floor's indirect light is gathered.
#[derive(Clone, Copy, Debug, ValueEnum)]
enum IndirectArg {
    /// Along lines across the image, each piece between two walls
    /// looking both ways
    Lines,
    /// By each pixel's own path samples, one direction each
    Samples,
}

/// What the cache holds.
#[derive(Clone, Copy, Debug, ValueEnum)]
enum CacheArg {
    /// Direct light on walls and on each pixel, and, with two or more
    /// bounces, what light goes on from each wall: paths end at the first
    /// diffuse wall they meet
    On,
    /// No cache: shadow rays at every diffuse wall, paths followed to the
    /// end
    Off,
    /// Direct light only: paths are followed from wall to wall (to see
    /// what the cache of light going on from walls buys)
    Direct,
}

impl CacheArg {
    /// The memo options that `cache` gives over `base` (the scene's,
    /// kept where `cache` is `None`).
    fn memo(cache: Option<CacheArg>, base: MemoOptions) -> MemoOptions {
        match cache {
            None => base,
            Some(CacheArg::On) => {
                let mut memo = base;
                memo.enabled = true;
                memo.onward = true;
                memo
            }
            Some(CacheArg::Off) => {
                let mut memo = base;
                memo.enabled = false;
                memo.onward = true;
                memo
            }
            Some(CacheArg::Direct) => {
                let mut memo = base;
                memo.enabled = true;
                memo.onward = false;
                memo
            }
        }
    }
}

/// A fast path that `--without` leaves out.
#[derive(Clone, Copy, Debug, ValueEnum)]
enum FastPathArg {
    Culling,
    Coherence,
    StrataLoops,
    Shortcut,
    Tables,
    Avx,
    DarkCells,
}

impl FastPathArg {
    fn path(self) -> FastPath {
        match self {
            FastPathArg::Culling => FastPath::Culling,
            FastPathArg::Coherence => FastPath::Coherence,
            FastPathArg::StrataLoops => FastPath::StrataLoops,
            FastPathArg::Shortcut => FastPath::Shortcut,
            FastPathArg::Tables => FastPath::Tables,
            FastPathArg::Avx => FastPath::Avx,
            FastPathArg::DarkCells => FastPath::DarkCells,
        }
    }
}

/// Which lights each receiver's shadow rays go to.
#[derive(Clone, Copy, Debug, Default, ValueEnum)]
enum LightsArg {
    /// The plan decides: `table` for a scene of more than 8 lights.
    #[default]
    Auto,
    /// One shadow ray to every light.
    Every,
    /// The brightest lights where the point lies, and one of the rest at
    /// random: a shadow ray or two per point however many lights.
    Table,
}

impl LightsArg {
    fn choice(self) -> LightChoice {
        match self {
            LightsArg::Auto => LightChoice::Auto,
            LightsArg::Every => LightChoice::Every,
            LightsArg::Table => LightChoice::Table,
        }
    }
}

impl IntegratorArg {
    fn integrator(self) -> Integrator {
        match self {
            IntegratorArg::Path => Integrator::Path,
            IntegratorArg::Original => Integrator::Original,
            IntegratorArg::Light => Integrator::Light,
        }
    }
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum IntegratorArg {
    /// Path tracing with next-event estimation at every diffuse vertex.
    Path,
    /// The original project's uniform bounce, aimed at the lights.
    Original,
    /// Light tracing: paths from the lights, spp x pixels of them.
    Light,
}

/// Runs flatray with `args` (the program name first), writing messages to
/// `out` and `err`; returns the exit code.
pub fn run<I, T>(args: I, out: &mut dyn Write, err: &mut dyn Write) -> i32
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    let cli = match Cli::try_parse_from(args) {
        Ok(cli) => cli,
        Err(e) => {
            let code = if e.use_stderr() { EXIT_USAGE } else { EXIT_OK };
            // Colour only for a terminal, and never with NO_COLOR set.
            let terminal = if e.use_stderr() {
                std::io::stderr().is_terminal()
            } else {
                std::io::stdout().is_terminal()
            };
            let colour = terminal && std::env::var_os("NO_COLOR").is_none_or(|v| v.is_empty());
            let text = if colour {
                e.render().ansi().to_string()
            } else {
                e.render().to_string()
            };
            let _ = if e.use_stderr() {
                write!(err, "{text}")
            } else {
                write!(out, "{text}")
            };
            return code;
        }
    };
    let mut out = Checked::new(out);
    let result = match cli.command {
        Command::Render(args) => render(args, &mut out, err),
        Command::Check { scenes, json } => check(&scenes, json, &mut out, err),
        Command::Plan {
            scene,
            bounces,
            specular,
            cache,
            caustics,
            lights,
            integrator,
            verbose,
            json,
        } => plan(
            &scene,
            (bounces, specular),
            (cache, caustics, lights),
            integrator,
            (verbose, json),
            (&mut out, err),
        ),
        Command::Converge(args) => converge::converge(args, &mut out, err),
        Command::Day(args) => day::day(args, &mut out, err),
        Command::Measure(args) => measure::measure(args, &mut out, err),
        Command::Serve(args) => serve::serve(args, &mut out, err),
        Command::Import(args) => import(args, &mut out, err),
        Command::Generate(args) => generate(args, &mut out),
        Command::Completions { shell } => {
            let mut command = <Cli as clap::CommandFactory>::command();
            clap_complete::generate(shell, &mut command, "flatray", &mut out);
            Ok(())
        }
        Command::Man { subcommand } => manual(subcommand.as_deref(), &mut out),
    };
    let result = result.and_then(|()| out.finish());
    match result {
        Ok(()) => EXIT_OK,
        Err(failure) => {
            let _ = writeln!(err, "error: {}", failure.message);
            failure.code
        }
    }
}

/// Prints the manual page of flatray, or of one of its subcommands
/// (`flatray-render(1)` and so on, as flatray's own page names them).
fn manual(subcommand: Option<&str>, out: &mut dyn Write) -> Result<(), Failure> {
    let command = <Cli as clap::CommandFactory>::command();
    let page = match subcommand {
        None => command,
        Some(name) => {
            let names: Vec<&str> = command.get_subcommands().map(|c| c.get_name()).collect();
            let Some(found) = command.find_subcommand(name) else {
                let near = flatray_io::did_you_mean(name, &names)
                    .map_or(String::new(), |n| format!(" (did you mean `{n}`?)"));
                return Err(Failure::usage(format!(
                    "man: no subcommand `{name}`{near}; the subcommands are {}",
                    names.join(", ")
                )));
            };
            // The page is `flatray-render(1)`, as man pages of
            // subcommands are named; its synopsis is the command as typed.
            found
                .clone()
                .display_name(format!("flatray-{name}"))
                .bin_name(format!("flatray {name}"))
        }
    };
    let source = format!("flatray {}", env!("CARGO_PKG_VERSION"));
    match clap_mangen::Man::new(page).source(source).render(out) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(Failure::other(format!("cannot write the manual: {e}")))
        }
        _ => Ok(()),
    }
}

/// Standard output that remembers its first failure, so that a summary
/// written to a full disk or a closed pipe fails the command (exit 1)
/// instead of vanishing.
struct Checked<'a> {
    inner: &'a mut dyn Write,
    failed: Option<std::io::Error>,
}

impl<'a> Checked<'a> {
    fn new(inner: &'a mut dyn Write) -> Checked<'a> {
        Checked {
            inner,
            failed: None,
        }
    }

    /// Flushes; the first failure of any write, if there was one.
    fn finish(mut self) -> Result<(), Failure> {
        if let Err(e) = self.inner.flush() {
            self.failed.get_or_insert(e);
        }
        match self.failed {
            None => Ok(()),
            // The reader has gone (`flatray plan | head -3`): nothing is
            // lost that anyone reads, as for any command-line tool.
            Some(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
            Some(e) => Err(Failure::other(format!(
                "cannot write to standard output: {e}"
            ))),
        }
    }
}

impl Write for Checked<'_> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        match self.inner.write(buf) {
            Ok(n) => Ok(n),
            Err(e) => {
                let kind = e.kind();
                self.failed.get_or_insert(e);
                Err(kind.into())
            }
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

mod converge;
mod day;
mod json;
mod measure;
mod serve;

/// A failure with its exit code.
pub(crate) struct Failure {
    code: i32,
    message: String,
}

impl Failure {
    fn usage(message: impl ToString) -> Failure {
        Failure {
            code: EXIT_USAGE,
            message: message.to_string(),
        }
    }

    fn other(message: impl ToString) -> Failure {
        Failure {
            code: EXIT_FAILURE,
            message: message.to_string(),
        }
    }
}

/// Loads a scene: any failure, to read it or to understand it, is a bad
/// scene (exit 2). A located error shows its line with a caret under the
/// column, and a hint for common mistakes.
pub(crate) fn load(path: &Path) -> Result<Loaded, Failure> {
    flatray_io::load(path).map_err(|e| {
        let mut message = e.to_string();
        if let Some((line, column)) = e.location()
            && let Ok(text) = std::fs::read_to_string(path)
            && let Some(source) = text
                .trim_start_matches('\u{feff}')
                .lines()
                .nth(line.saturating_sub(1))
        {
            message.push_str(&snippet(source, line, column));
            if let Some(hint) = hint(&message, source) {
                message.push_str(&format!("\n  hint: {hint}"));
            }
        }
        Failure::usage(message)
    })
}

/// The source line and a caret under `column` (in characters), as rustc
/// shows them.
fn snippet(source: &str, line: usize, column: usize) -> String {
    let number = line.to_string();
    let pad = " ".repeat(number.len());
    let shown: String = source.chars().take(160).collect();
    let before: String = source
        .chars()
        .take(column.saturating_sub(1))
        .map(|c| if c == '\t' { '\t' } else { ' ' })
        .collect();
    format!("\n {pad} |\n {number} | {shown}\n {pad} | {before}^")
}

/// A suggestion for the mistakes a scene's author makes most often.
fn hint(message: &str, source: &str) -> Option<&'static str> {
    let compact: String = source.chars().filter(|c| !c.is_whitespace()).collect();
    if compact.contains("Color(")
        && !compact.contains("Color((")
        && message.contains("Expected opening `(`")
    {
        return Some("a colour is a tuple inside the variant: `Color((0.8, 0.75, 0.65))`");
    }
    if message.contains("Expected opening `(`") && compact.contains("Image(") {
        return Some("a floor image is a path in quotes: `Image(\"floor.png\")`");
    }
    if message.contains("Unexpected field") || message.contains("unknown field") {
        return Some("every field is listed in docs/scene-format.md");
    }
    None
}

/// Prints a loaded scene's warnings, each with its location.
fn warn(scene: &Path, loaded: &Loaded, err: &mut dyn Write) {
    for w in &loaded.warnings {
        let _ = writeln!(
            err,
            "{}:{}:{}: warning: {}",
            scene.display(),
            w.line,
            w.column,
            w.message
        );
    }
}

fn check(
    scenes: &[PathBuf],
    json: bool,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> Result<(), Failure> {
    let mut refused = 0;
    let mut objects = Vec::new();
    for scene in scenes {
        if json {
            match flatray_io::load(scene) {
                Ok(loaded) => objects.push(json::checked(scene, &loaded)),
                Err(e) => {
                    refused += 1;
                    objects.push(json::refused(scene, &e));
                }
            }
            continue;
        }
        let loaded = match load(scene) {
            Ok(loaded) => loaded,
            Err(failure) => {
                refused += 1;
                let _ = writeln!(err, "error: {}", failure.message);
                continue;
            }
        };
        warn(scene, &loaded, err);
        let counts = loaded.counts;
        let emitting = if counts.emitting_walls > 0 {
            format!(" ({} emitting)", counts.emitting_walls)
        } else {
            String::new()
        };
        let _ = writeln!(
            out,
            "{}: ok ({}{emitting}, {}, {}, canvas {} x {})",
            scene.display(),
            flatray_io::counted(counts.walls, "wall", "walls"),
            flatray_io::counted(counts.lights, "light", "lights"),
            flatray_io::counted(counts.glass, "glass body", "glass bodies"),
            loaded.scene.canvas().width,
            loaded.scene.canvas().height
        );
    }
    if json {
        let object = serde_json::json!({"format": json::FORMAT, "scenes": objects});
        let _ = writeln!(out, "{object:#}");
    }
    match refused {
        0 => Ok(()),
        // Each error is printed already: exit 2 with a count.
        n if json => Err(Failure::usage(format!(
            "{} refused",
            flatray_io::counted(n, "scene", "scenes")
        ))),
        n => Err(Failure::usage(format!(
            "{} of {} refused",
            n,
            flatray_io::counted(scenes.len(), "scene", "scenes")
        ))),
    }
}

fn plan(
    scene: &Path,
    (bounces, specular): (Option<u32>, Option<u32>),
    (cache, caustics, lights): (Option<CacheArg>, Option<Switch>, Option<LightsArg>),
    integrator: Option<IntegratorArg>,
    (verbose, as_json): (bool, bool),
    (out, err): (&mut dyn Write, &mut dyn Write),
) -> Result<(), Failure> {
    let loaded = load(scene)?;
    if !as_json {
        warn(scene, &loaded, err);
    }
    let options = {
        let mut options = loaded.options;
        options.bounces = bounces.unwrap_or(loaded.options.bounces);
        options.specular = specular.unwrap_or(loaded.options.specular);
        options.integrator =
            integrator.map_or(loaded.options.integrator, IntegratorArg::integrator);
        options.memo = CacheArg::memo(cache, loaded.options.memo);
        options.caustics = caustics.map_or(loaded.options.caustics, Switch::on);
        options.light_choice = lights.map_or(loaded.options.light_choice, LightsArg::choice);
        options
    };
    let plan = flatray_tracer::Plan::new(&loaded.scene, &options);
    if as_json {
        let mut object = json::plan(&plan, &options);
        object["format"] = json::FORMAT.into();
        object["scene"] = scene.display().to_string().into();
        object["warnings"] = json::warnings(&loaded.warnings);
        let _ = writeln!(out, "{object:#}");
    } else if verbose {
        let _ = writeln!(out, "{}", plan.verbose());
    } else {
        let _ = writeln!(out, "{}", plan.summary());
    }
    Ok(())
}

/// `render`, once, or with `--watch` again after every change to the
/// scene or its floor image, until interrupted.
fn render(args: RenderArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<(), Failure> {
    if !args.watch {
        return render_once(&args, out, err);
    }
    loop {
        let inputs = flatray_io::load(&args.scene)
            .map_or_else(|_| vec![args.scene.clone()], |loaded| loaded.inputs);
        let before = stamps(&inputs);
        if let Err(failure) = render_once(&args, out, err) {
            let _ = writeln!(err, "error: {}", failure.message);
        }
        let _ = out.flush();
        let _ = writeln!(
            err,
            "watching {} for changes (Ctrl-C to stop)",
            args.scene.display()
        );
        while stamps(&inputs) == before {
            std::thread::sleep(std::time::Duration::from_millis(250));
        }
    }
}

/// The modification times and lengths of `files` (none for a file that
/// cannot be read).
fn stamps(files: &[PathBuf]) -> Vec<Option<(std::time::SystemTime, u64)>> {
    files.iter().map(|f| stamp(f)).collect()
}

/// A file's modification time and length: what changes when it is
/// saved. `None` when it cannot be read.
pub(crate) fn stamp(path: &Path) -> Option<(std::time::SystemTime, u64)> {
    let m = std::fs::metadata(path).ok()?;
    Some((m.modified().ok()?, m.len()))
}

fn render_once(args: &RenderArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<(), Failure> {
    let started = Instant::now();
    let output = match &args.output {
        Some(path) => path.clone(),
        None => default_output(&args.scene),
    };
    let format = Format::from_path(&output).map_err(Failure::usage)?;
    if args.draw_walls && format != Format::Png {
        return Err(Failure::usage(
            "--draw-walls: walls are drawn on PNG images only (an EXR keeps the linear values untouched)",
        ));
    }
    if !(args.scale.is_finite() && args.scale > 0.0) {
        return Err(Failure::usage(format!(
            "--scale: expected a finite number > 0, found {}",
            args.scale
        )));
    }
    if let Some(exposure) = args.exposure
        && !(exposure > 0.0 && exposure <= flatray_io::format::MAX_INTENSITY)
    {
        return Err(Failure::usage(format!(
            "--exposure: expected a number > 0 and at most {:e}, found {exposure}",
            flatray_io::format::MAX_INTENSITY
        )));
    }

    let loaded = load(&args.scene)?;
    warn(&args.scene, &loaded, err);
    check_output(&output, &loaded.inputs, "render")?;
    let options = {
        let mut options = RenderOptions::default();
        options.samples = args.spp.unwrap_or(loaded.options.samples);
        options.bounces = args.bounces.unwrap_or(loaded.options.bounces);
        options.specular = args.specular.unwrap_or(loaded.options.specular);
        options.seed = args.seed.unwrap_or(loaded.options.seed);
        options.exposure = args.exposure.unwrap_or(loaded.options.exposure);
        options.scale = args.scale;
        options.integrator = args
            .integrator
            .map_or(loaded.options.integrator, IntegratorArg::integrator);
        options.memo = CacheArg::memo(args.cache, loaded.options.memo);
        options.caustics = args.caustics.map_or(loaded.options.caustics, Switch::on);
        options = options.with_reference(args.reference);
        options = options.with_fast_paths(
            args.without
                .iter()
                .fold(FastPaths::ALL, |paths, p| paths.without(p.path())),
        );
        options.light_choice = args
            .lights
            .map_or(loaded.options.light_choice, LightsArg::choice);
        options.adaptive = args.adaptive;
        options.floor_lines = !matches!(args.indirect, Some(IndirectArg::Samples));
        options
    };
    if let Some(map) = &args.write_spp {
        if Format::from_path(map).map_err(Failure::usage)? != Format::Png {
            return Err(Failure::usage(format!(
                "--write-spp: the map of samples is a PNG image; {} is not a .png",
                map.display()
            )));
        }
        if map == &output {
            return Err(Failure::usage(format!(
                "--write-spp: {} is also the rendered image",
                map.display()
            )));
        }
        check_output(map, &loaded.inputs, "render")?;
    }
    let (width, height) = checked_size(&loaded, options.scale)?;
    let pixels = width as u64 * height as u64;
    let loaded_at = Instant::now();

    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    if let Some(n) = args.threads
        && n as usize > cores
    {
        let _ = writeln!(
            err,
            "warning: --threads {n} on {}: more threads than cores make the render slower, not faster",
            flatray_io::counted(cores, "core", "cores")
        );
    }
    let pool = match args.threads {
        None => None,
        Some(n) => Some(
            rayon::ThreadPoolBuilder::new()
                .num_threads(n as usize)
                .build()
                .map_err(|e| Failure::other(format!("cannot start {n} threads: {e}")))?,
        ),
    };
    let write = |rendered: &flatray_tracer::Rendered| {
        if args.draw_walls {
            flatray_io::write_png_with_walls(
                &rendered.image,
                loaded.tonemap,
                &loaded.scene,
                &output,
            )
        } else {
            flatray_io::write_image(&rendered.image, loaded.tonemap, &output)
        }
        .map_err(Failure::other)
    };
    let (rendered, options, passes) = match (args.target_error, args.time) {
        (None, None) => {
            let bar = progress_bar(pixels * options.samples as u64, args.quiet, "rendering");
            let progress = |n: u64| bar.inc(n);
            let rendered = match &pool {
                None => flatray_tracer::render(&loaded.scene, &options, &progress),
                Some(pool) => {
                    pool.install(|| flatray_tracer::render(&loaded.scene, &options, &progress))
                }
            };
            bar.finish_and_clear();
            (rendered, options, 1)
        }
        (target, time) => {
            let stop = Stop::new(target, time, loaded_at, args.error_metric.metric())?;
            let in_pool = |work: &mut (dyn FnMut() + Send)| match &pool {
                None => work(),
                Some(pool) => pool.install(work),
            };
            let mut progressive = None;
            in_pool(&mut || {
                progressive = Some(flatray_tracer::Progressive::new(&loaded.scene, &options))
            });
            let Some(mut progressive) = progressive else {
                return Err(Failure::other("the render could not start".to_string()));
            };
            let mut passes = 0;
            let rendered = loop {
                let done = progressive.samples();
                let Some(end) = stop.next_end(&progressive, passes) else {
                    break progressive.rendered();
                };
                let what = format!("pass {} ({} to {end} spp)", passes + 1, done);
                let bar = progress_bar(pixels * (end - done) as u64, args.quiet, &what);
                let progress = |n: u64| bar.inc(n);
                in_pool(&mut || {
                    progressive.pass(end, &progress);
                });
                bar.finish_and_clear();
                passes += 1;
                if args.write_passes {
                    write(&progressive.rendered())?;
                    kept(Some(format!(
                        "{} holds the last finished pass: {} spp",
                        output.display(),
                        progressive.samples()
                    )));
                }
            };
            let samples = progressive.samples();
            (
                rendered,
                {
                    let mut options = options;
                    options.samples = samples;
                    options
                },
                passes,
            )
        }
    };
    let rendered_at = Instant::now();
    write(&rendered)?;
    kept(None);
    if let Some(map) = &args.write_spp {
        write_samples_map(&rendered, (width, height), map).map_err(Failure::other)?;
    }
    let written_at = Instant::now();
    let mean_samples = rendered.samples.iter().map(|&n| n as f64).sum::<f64>()
        / rendered.samples.len().max(1) as f64;

    if args.json {
        let plan = flatray_tracer::Plan::new(&loaded.scene, &options);
        let mut object = json::stats(&rendered.stats);
        object["format"] = json::FORMAT.into();
        object["output"] = output.display().to_string().into();
        object["width"] = width.into();
        object["height"] = height.into();
        object["samples"] = options.samples.into();
        object["mean_samples"] = mean_samples.into();
        object["passes"] = passes.into();
        object["plan"] = json::plan(&plan, &options);
        object["warnings"] = json::warnings(&loaded.warnings);
        object["seconds"] = serde_json::json!({
            "load": (loaded_at - started).as_secs_f64(),
            "render": (rendered_at - loaded_at).as_secs_f64(),
            "write": (written_at - rendered_at).as_secs_f64(),
            "total": (written_at - started).as_secs_f64(),
        });
        let _ = writeln!(out, "{object:#}");
        return Ok(());
    }
    let _ = writeln!(
        out,
        "wrote {} ({width} x {height}, {} spp, {} bounce{}{}) in {:.2} s; noise {}",
        output.display(),
        if options.adaptive {
            format!("{mean_samples:.0} (at most {})", options.samples)
        } else {
            options.samples.to_string()
        },
        options.bounces,
        if options.bounces == 1 { "" } else { "s" },
        if passes > 1 {
            format!(", {passes} passes")
        } else {
            String::new()
        },
        (written_at - started).as_secs_f64(),
        rendered.stats.noise
    );
    if rendered.stats.physics.nonfinite_samples > 0 {
        let _ = writeln!(
            err,
            "warning: {} samples were not finite and were left out",
            rendered.stats.physics.nonfinite_samples
        );
    }
    if args.stats || args.verbose {
        let plan = flatray_tracer::Plan::new(&loaded.scene, &options);
        if args.verbose {
            let _ = writeln!(out, "plan\n{}", plan.verbose());
            let _ = writeln!(out, "{}", rendered.stats);
        } else {
            let _ = writeln!(out, "plan\n{}", plan.summary());
            let _ = writeln!(out, "{}", rendered.stats.summary());
        }
        let _ = writeln!(out, "seconds");
        let _ = writeln!(
            out,
            "  load             {:>14.3}",
            (loaded_at - started).as_secs_f64()
        );
        let _ = writeln!(
            out,
            "  render           {:>14.3}",
            (rendered_at - loaded_at).as_secs_f64()
        );
        let _ = writeln!(
            out,
            "  write            {:>14.3}",
            (written_at - rendered_at).as_secs_f64()
        );
    }
    Ok(())
}

fn generate(args: GenerateArgs, out: &mut dyn Write) -> Result<(), Failure> {
    if !(0.0..=1.0).contains(&args.mirrors) {
        return Err(Failure::usage(format!(
            "--mirrors: expected a share from 0 to 1, found {}",
            args.mirrors
        )));
    }
    let plan = flatray_io::generate::Apartment {
        rooms: args.rooms,
        lamps_per_room: args.lamps,
        mirrors: args.mirrors,
        sun: !args.no_sun,
        seed: args.seed,
    };
    check_output(&args.output, &[], "generate")?;
    keep_scene(&args.output, args.force)?;
    flatray_io::write_text(&args.output, &plan.to_ron()).map_err(Failure::other)?;
    let _ = writeln!(out, "wrote {}", args.output.display());
    Ok(())
}

fn import(args: ImportArgs, out: &mut dyn Write, err: &mut dyn Write) -> Result<(), Failure> {
    use flatray_io::import::{Doors, ImportOptions, OpenPortals};
    let options = ImportOptions {
        scale: args.scale,
        tolerance: args.tolerance,
        walls_layer: args.walls_layer,
        lights_layer: args.lights_layer,
        floor_image: args.floor_image,
        doors: match args.doors {
            DoorsArg::AsDrawn => Doors::AsDrawn,
            DoorsArg::Open => Doors::Open,
            DoorsArg::Closed => Doors::Closed,
        },
        open_portals: match args.open_portals {
            OpenPortalsArg::Windows => OpenPortals::Windows,
            OpenPortalsArg::Doors => OpenPortals::Doors,
        },
        lights: args.lights == MapLightsArg::Keep,
    };
    let output = match args.output {
        Some(path) => path,
        None => {
            let stem = args
                .plan
                .file_stem()
                .map_or("plan".to_string(), |s| s.to_string_lossy().into_owned());
            PathBuf::from(format!("{stem}.ron"))
        }
    };
    let imported = import_to(&args.plan, &options, &output, args.force, err)?;
    let _ = writeln!(out, "wrote {} ({imported})", output.display());
    Ok(())
}

/// Imports `plan` into the scene file `output`, and its floor image
/// beside it where it has one, replacing neither an existing file
/// (unless `force`) nor the plan; the notes and warnings go to `err`.
/// Returns what was imported, for the caller's report.
pub(crate) fn import_to(
    plan: &Path,
    options: &flatray_io::import::ImportOptions,
    output: &Path,
    force: bool,
    err: &mut dyn Write,
) -> Result<flatray_io::import::Imported, Failure> {
    // A plan that cannot be read or understood is bad input (exit 2).
    let mut imported = flatray_io::import::import(plan, options).map_err(Failure::usage)?;
    check_output(output, &[plan.to_path_buf()], "import")?;
    keep_scene(output, force)?;
    if let Some(floor) = imported.name_floor_for(output) {
        check_output(&floor, &[plan.to_path_buf()], "import")?;
        keep_scene(&floor, force)?;
    }
    imported
        .write(output, plan, force)
        .map_err(Failure::other)?;
    for line in imported.mapping.iter().chain(&imported.notes) {
        let _ = writeln!(err, "note: {line}");
    }
    for warning in &imported.warnings {
        let _ = writeln!(err, "warning: not imported: {warning}");
    }
    Ok(imported)
}

/// When `--target-error` and `--time` stop a render taken pass by pass.
struct Stop {
    /// The relative noise to reach, and the seconds from `since` to stay
    /// within.
    target: Option<f64>,
    time: Option<f64>,
    since: Instant,
    /// The error the target is of.
    metric: flatray_tracer::metrics::ErrorMetric,
    /// When the last pass started, and the samples then.
    last: std::cell::Cell<(Instant, u32)>,
}

impl Stop {
    fn new(
        target: Option<f64>,
        time: Option<f64>,
        since: Instant,
        metric: flatray_tracer::metrics::ErrorMetric,
    ) -> Result<Stop, Failure> {
        let target = target.map(|t| t / 100.0);
        if let Some(t) = target
            && !(t.is_finite() && t > 0.0)
        {
            return Err(Failure::usage(format!(
                "--target-error: expected a percentage > 0, found {}",
                t * 100.0
            )));
        }
        if let Some(t) = time
            && !(t.is_finite() && t > 0.0)
        {
            return Err(Failure::usage(format!(
                "--time: expected seconds > 0, found {t}"
            )));
        }
        Ok(Stop {
            target,
            time,
            since,
            metric,
            last: std::cell::Cell::new((Instant::now(), 0)),
        })
    }

    /// Where the next pass should end, or `None` to stop: once the noise
    /// is at most the target. Each pass doubles the samples
    /// ([`flatray_tracer::next_pass_end`]), unless the time left (at the
    /// last pass's seconds per sample) has room for fewer: then the pass
    /// ends where the time does, and is the last, since a render of more
    /// samples would not have taken it.
    fn next_end(&self, progressive: &flatray_tracer::Progressive, passes: u32) -> Option<u32> {
        let done = progressive.samples();
        let next = progressive.next_end()?.min(flatray_io::format::MAX_SAMPLES);
        if next <= done {
            return None;
        }
        let (started, before) = self.last.get();
        self.last.set((Instant::now(), done));
        if passes == 0 {
            return Some(next);
        }
        let per_sample = started.elapsed().as_secs_f64() / (done - before).max(1) as f64;
        if let (Some(t), Some(e)) = (
            self.target,
            self.metric.of_noise(&progressive.rendered().stats.noise),
        ) && e <= t
        {
            return None;
        }
        // Samples the time leaves room for: the whole next pass, or a
        // last pass that ends short of it.
        let affordable = match self.time {
            Some(t) => {
                let left = t - self.since.elapsed().as_secs_f64();
                done as f64 + (left / per_sample.max(1e-12)).floor()
            }
            None => f64::INFINITY,
        };
        let end = affordable.min(next as f64);
        (end > done as f64).then(|| (end as u32).min(next))
    }
}

/// The image size at `scale`, or a usage error when it is more than
/// flatray renders.
pub(crate) fn checked_size(loaded: &Loaded, scale: f64) -> Result<(u32, u32), Failure> {
    flatray_tracer::checked_image_size(&loaded.scene, scale)
        .map_err(|why| Failure::usage(format!("--scale {scale}: {why}")))
}

/// Refuses, before any work, an output that cannot be written or must not
/// be: in a folder that does not exist, a folder itself, a read-only file,
/// or one of the render's own inputs (the scene, its floor image).
fn check_output(output: &Path, inputs: &[PathBuf], command: &str) -> Result<(), Failure> {
    let folder = match output.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !folder.is_dir() {
        return Err(Failure::usage(format!(
            "{}: cannot write it: the folder {} does not exist",
            output.display(),
            folder.display()
        )));
    }
    if let Ok(metadata) = std::fs::metadata(output) {
        if metadata.is_dir() {
            return Err(Failure::usage(format!(
                "{}: cannot write it: it is a folder",
                output.display()
            )));
        }
        if metadata.permissions().readonly() {
            return Err(Failure::usage(format!(
                "{}: the file is read-only; flatray will not replace it",
                output.display()
            )));
        }
    }
    for input in inputs {
        if same_file(output, input) {
            return Err(Failure::usage(format!(
                "{}: the output is an input of this {command} ({}); choose another name with -o",
                output.display(),
                input.display()
            )));
        }
    }
    Ok(())
}

/// Refuses to replace an existing file that a command writes as the
/// user's work (a scene, its floor image) unless `force`.
fn keep_scene(path: &Path, force: bool) -> Result<(), Failure> {
    if !force && std::fs::symlink_metadata(path).is_ok() {
        return Err(Failure::usage(format!(
            "{}: the file exists; flatray will not replace it without --force (or choose another name with -o)",
            path.display()
        )));
    }
    Ok(())
}

/// Whether `a` and `b` name the same file: the same path once links and
/// `..` are resolved, or (on Unix) the same file on disk.
fn same_file(a: &Path, b: &Path) -> bool {
    let resolved = |p: &Path| -> Option<PathBuf> {
        if let Ok(p) = std::fs::canonicalize(p) {
            return Some(p);
        }
        let folder = match p.parent() {
            Some(f) if !f.as_os_str().is_empty() => f,
            _ => Path::new("."),
        };
        Some(std::fs::canonicalize(folder).ok()?.join(p.file_name()?))
    };
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(x), Ok(y)) = (std::fs::metadata(a), std::fs::metadata(b))
            && (x.dev(), x.ino()) == (y.dev(), y.ino())
        {
            return true;
        }
    }
    matches!((resolved(a), resolved(b)), (Some(x), Some(y)) if x == y)
}

/// On the first SIGINT or SIGTERM (Ctrl-C): removes the temporary file of
/// an image being written and exits with 130. Installed once per process;
/// a second call does nothing.
pub fn exit_cleanly_on_interrupt() {
    let _ = ctrlc::set_handler(|| {
        flatray_io::remove_pending_files();
        let note = KEPT
            .try_lock()
            .ok()
            .and_then(|k| k.clone())
            .map_or(String::new(), |k| format!("; {k}"));
        let _ = writeln!(std::io::stderr(), "\ninterrupted{note}");
        std::process::exit(130);
    });
}

/// What an interrupt leaves behind, said when it comes: the image of the
/// last finished pass that `--write-passes` wrote.
static KEPT: std::sync::Mutex<Option<String>> = std::sync::Mutex::new(None);

/// Writes the samples each pixel of `rendered` took as a grey PNG, white
/// for the most.
fn write_samples_map(
    rendered: &flatray_tracer::Rendered,
    (width, height): (u32, u32),
    path: &Path,
) -> Result<(), String> {
    let most = rendered.samples.iter().copied().max().unwrap_or(0).max(1) as f32;
    let mut image = flatray_tracer::Image::new(width, height);
    for (pixel, &n) in image.pixels.iter_mut().zip(&rendered.samples) {
        *pixel = [n as f32 / most; 3];
    }
    flatray_io::write_png(&image, flatray_io::ToneMap::Clamp, path).map_err(|e| e.to_string())
}

fn kept(what: Option<String>) {
    if let Ok(mut k) = KEPT.lock() {
        *k = what;
    }
}

/// A progress bar with an ETA on stderr, hidden with `--quiet` or when
/// stderr is not a terminal.
pub(crate) fn progress_bar(total: u64, quiet: bool, what: &str) -> ProgressBar {
    if quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr());
    let template = format!(
        "{{spinner}} {what} [{{bar:40}}] {{percent:>3}}%  {{elapsed_precise}} elapsed, {{sane_eta}}"
    );
    if let Ok(style) = ProgressStyle::with_template(&template) {
        // No estimate until a little of the work is done: before the first
        // samples (while the memo fills) the rate says nothing yet.
        let style = style.with_key(
            "sane_eta",
            |state: &indicatif::ProgressState, w: &mut dyn std::fmt::Write| {
                let _ = if state.fraction() < 0.02 {
                    write!(w, "estimating")
                } else {
                    write!(w, "ETA {:#}", indicatif::HumanDuration(state.eta()))
                };
            },
        );
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}

fn default_output(scene: &Path) -> PathBuf {
    let stem = scene
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "render".to_string());
    PathBuf::from(format!("{stem}.png"))
}
