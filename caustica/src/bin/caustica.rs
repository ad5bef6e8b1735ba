//! The `caustica` command line: `render`, `scenes`, `backends`, `techniques`, `reference`, `report`.
//!
//! Nothing is printed with `print!` or `eprint!` (they panic when the stream fails): stdout
//! goes through [`Console`], whose write errors end the command (a closed pipe quietly, any
//! other error with a message), and stderr through [`note!`], which cannot fail.

use caustica::output::{write_exr, write_png};
use caustica::scene::{builtin, format};
use caustica::technique_spec::{get_setting, put_setting};
use caustica::techniques::{create, technique_names, TECHNIQUES};
use caustica::{open_backend, FrameStats, Scene};
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use std::fmt;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Why a command stopped before it finished.
enum Stop {
    /// The command failed: `error: MESSAGE` on stderr, exit status 1.
    Failed(String),
    /// Stdout is a pipe whose reader has gone (`caustica scenes --export prism | head`).
    /// The program ends at once, without a message and with status 0: the reader stopped
    /// because it had what it wanted, which is no failure of this command, and a script
    /// under `set -o pipefail` must not fail because `head` read one line. (The other
    /// convention, dying of SIGPIPE with status 141, makes exactly those scripts fail.)
    /// Every command writes its files before its stdout lines, so a closed stdout loses
    /// nothing but those lines.
    StdoutClosed,
}

impl From<String> for Stop {
    fn from(message: String) -> Stop {
        Stop::Failed(message)
    }
}

impl From<&str> for Stop {
    fn from(message: &str) -> Stop {
        Stop::Failed(message.into())
    }
}

/// Stdout, with its write errors returned: a closed pipe is [`Stop::StdoutClosed`], any
/// other error (a full disk behind `> file`, an I/O error) a failure that names stdout.
struct Console {
    out: std::io::StdoutLock<'static>,
}

impl Console {
    fn new() -> Console {
        Console {
            out: std::io::stdout().lock(),
        }
    }

    /// Writes `text` as it is (no newline added).
    fn write(&mut self, text: fmt::Arguments) -> Result<(), Stop> {
        self.out.write_fmt(text).map_err(stdout_error)
    }

    /// Writes `text` and a newline.
    fn line(&mut self, text: fmt::Arguments) -> Result<(), Stop> {
        self.write(format_args!("{text}\n"))
    }

    /// Writes out what is buffered, so that its error is seen here, not lost at exit.
    fn flush(&mut self) -> Result<(), Stop> {
        self.out.flush().map_err(stdout_error)
    }
}

fn stdout_error(e: std::io::Error) -> Stop {
    if e.kind() == std::io::ErrorKind::BrokenPipe {
        Stop::StdoutClosed
    } else {
        Stop::Failed(format!("writing to stdout: {e}"))
    }
}

/// One line on stderr (progress, warnings, the final error). A stderr that cannot be
/// written is ignored: there is no other place to report that to, and the exit status
/// still tells how the command went, so the command carries on with its work.
fn note_line(text: fmt::Arguments) {
    let _ = writeln!(std::io::stderr().lock(), "{text}");
}

/// `outln!(console, "format", args...)`: a line on stdout, `Result<(), Stop>`.
macro_rules! outln {
    ($console:expr, $($arg:tt)*) => {
        $console.line(format_args!($($arg)*))
    };
}

/// `note!("format", args...)`: a line on stderr that never fails (see [`note_line`]).
macro_rules! note {
    ($($arg:tt)*) => {
        note_line(format_args!($($arg)*))
    };
}

/// After a run has written its files (`written`) into the output folder `out`: one
/// warning line on stderr naming the files there that the run did not write
/// ([`caustica::output::files_not_written`]; the first five, then how many more), which
/// are left as they were, so that an earlier run's outputs are not taken for this one's.
/// A folder that cannot be listed is passed over: the run's own files are written.
fn note_files_not_written(out: &Path, written: &[PathBuf]) {
    const SHOWN: usize = 5;
    let Ok(stale) = caustica::output::files_not_written(out, written) else {
        return;
    };
    if stale.is_empty() {
        return;
    }
    let mut names = stale
        .iter()
        .take(SHOWN)
        .map(|n| n.escape_debug().to_string())
        .collect::<Vec<_>>()
        .join(", ");
    if stale.len() > SHOWN {
        names += &format!(" and {} more", stale.len() - SHOWN);
    }
    let (count, was, it_is, it) = match stale.len() {
        1 => ("1 file".to_string(), "was", "it is", "it"),
        n => (format!("{n} files"), "were", "they are", "they"),
    };
    note!(
        "warning: {count} in {} {was} not written by this run ({names}): {it_is} from an \
         earlier run and {was} left as {it} {was}",
        out.display()
    );
}

#[derive(Parser)]
#[command(
    name = "caustica",
    version,
    about = "Real-time photon-mapping techniques for caustics"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render one frame of a scene and write EXR images, a PNG and stats.json.
    Render {
        /// Built-in scene name (see `caustica scenes`) or a scene file (caustica's JSON,
        /// or glTF 2.0: .gltf or .glb).
        #[arg(long, default_value = "sphere")]
        scene: String,
        /// Technique (see `caustica techniques`).
        #[arg(long, default_value = "sspm")]
        technique: String,
        /// Backend: auto, cpu, vulkan, wgpu, opencl (see `caustica backends`).
        #[arg(long, default_value = "cpu")]
        backend: String,
        /// Photon grid per light, WxH (default: the settings file's, else 1024x1024).
        #[arg(long, allow_hyphen_values = true, value_parser = parse_grid)]
        photons: Option<(u32, u32)>,
        /// Image size WxH (default: the scene camera's).
        #[arg(long, allow_hyphen_values = true, value_parser = parse_size)]
        size: Option<(u32, u32)>,
        /// Frame seed of the random numbers.
        #[arg(long, allow_negative_numbers = true)]
        seed: Option<u32>,
        /// Exposure multiplier for the PNG (EXR files are linear and unscaled).
        #[arg(long, allow_negative_numbers = true, default_value_t = 1.0, value_parser = parse_exposure)]
        exposure: f32,
        /// Settings file (a JSON object of the technique's settings, e.g. `{"frame":
        /// {"seed": 7}, "screen": {"filter": "bilateral"}}`; the flat objects of earlier
        /// versions still load) applied before the flags above.
        #[arg(long)]
        settings: Option<PathBuf>,
        /// The technique's caustic filter: Sspm's `screen.filter`, density (default: adapts
        /// to the photons, keeps the flux) or bilateral (Kim 2019's); CausticMap's and
        /// AdaptiveCaustics' `atlas.gather`, density (default) or box (Vanderstichelen
        /// 2021's 3x3); AdaptiveCaustics with `deposit: screen` in the settings file: its
        /// `screen.filter`, as Sspm's.
        #[arg(long, value_parser = ["density", "bilateral", "box"])]
        filter: Option<String>,
        /// Frames to render; the last is written. Above 1, a technique with progressive
        /// accumulation (`frame.accumulate`, every technique) sums the frames' photons as one
        /// frame of all of them; with `accumulate: false` in the settings each frame gets a
        /// new seed.
        #[arg(long, allow_negative_numbers = true, default_value_t = 1,
              value_parser = clap::value_parser!(u32).range(1..))]
        frames: u32,
        /// Seconds of scene time between frames: the scene's height fields (the `pool`'s
        /// water) become instances whose waves travel as deep-water waves do
        /// (`Wave::advanced`), each frame's new surface given to the technique through
        /// `set_object_vertices` (no rebuild), and every frame's composite is written as
        /// NAME_fNNN_composite.png. Frames keep one seed and do not accumulate unless the
        /// settings say so.
        #[arg(long, allow_negative_numbers = true)]
        animate: Option<f32>,
        /// Output directory.
        #[arg(long, default_value = "out")]
        out: PathBuf,
    },
    /// List the built-in scenes, or print one in the scene file format.
    Scenes {
        /// Print this built-in scene (save it, edit it, load it with --scene FILE).
        #[arg(long)]
        export: Option<String>,
        /// Format of --export: json (caustica's scene format) or gltf (glTF 2.0, one
        /// embedded buffer, for other tools).
        #[arg(long, default_value = "json", value_parser = ["json", "gltf"], requires = "export")]
        format: String,
    },
    /// List every backend, whether it works on this machine, its device type and the
    /// order in which `--backend auto` prefers them.
    Backends,
    /// List the techniques.
    Techniques,
    /// The independent caustic reference of a scene: a brute-force f64 light tracer's
    /// camera-space caustic radiance and its error bar (docs/performance.md), cached as
    /// EXR (mean, standard error) with a JSON sidecar; prints the sidecar.
    Reference {
        /// Built-in scene name or a scene file (caustica's JSON, or glTF 2.0: .gltf or
        /// .glb).
        #[arg(long, default_value = "sphere")]
        scene: String,
        /// Image size WxH.
        #[arg(long, allow_hyphen_values = true, default_value = "480x270", value_parser = parse_size)]
        size: (u32, u32),
        /// Photons per light and batch.
        #[arg(long, allow_negative_numbers = true, default_value_t = 1 << 22)]
        photons: u64,
        /// Independent batches (the error bar is their spread; at least 2).
        #[arg(long, allow_negative_numbers = true, default_value_t = 16)]
        batches: u32,
        /// Seed of the batches' random streams.
        #[arg(long, allow_negative_numbers = true, default_value_t = 1)]
        seed: u64,
        /// Spheres as the exact sphere (analytic) or the scene's tessellated mesh (mesh).
        #[arg(long, default_value = "analytic", value_parser = ["analytic", "mesh"])]
        spheres: String,
        /// What a silhouette pixel measures: centre-surface (default), the radiance of the
        /// surface the pixel's centre sees, every photon on it counted, hidden from the eye
        /// or not, as the caustic techniques' store test counts them; eye-visible, the flux
        /// the eye sees through the pixel's footprint (hidden photons dropped). The two
        /// differ only in pixels that straddle a silhouette.
        #[arg(long, default_value = "centre-surface", value_parser = ["centre-surface", "eye-visible"])]
        silhouette: String,
        /// Cache directory.
        #[arg(long, default_value = "out/references")]
        cache: PathBuf,
    },
    /// Error against run time for every scene x technique x backend x photon budget:
    /// prints a table, writes report.json and a log-log plot per scene. The caustic
    /// techniques (sspm, caustic-map, adaptive-caustics) are measured against the
    /// independent f64 light tracer's image of the same scene and camera (`caustica
    /// reference`), its relative standard error beside each error, and against their own
    /// converged estimate (Sspm's raw deposit) in a second column; photon-gi against its
    /// converged deposit only (the tracer covers caustic paths, not indirect light). The
    /// table's caption names the silhouette definition (--silhouette).
    Report {
        /// Comma-separated scenes (built-in names or scene files).
        #[arg(long, default_value = "sphere,cornell")]
        scenes: String,
        /// Comma-separated techniques, each optionally with settings set over the others'
        /// (`adaptive-caustics:deposit=screen+metric=level`)
        #[arg(long, default_value = "sspm")]
        techniques: String,
        /// Comma-separated backends.
        #[arg(long, default_value = "cpu")]
        backends: String,
        /// Comma-separated photon grids per light.
        #[arg(long, default_value = "256x256,512x512,1024x1024")]
        budgets: String,
        /// Frames measured per combination (after one warm-up frame), seeds 1..=N.
        #[arg(long, default_value_t = 5)]
        repeats: usize,
        /// Comma-separated frames accumulated per run (`accumulate: true`, timed to the
        /// last frame; techniques without accumulation are skipped beyond 1).
        #[arg(long, default_value = "1")]
        frames: String,
        /// Image size WxH of the measurements and the references.
        #[arg(long, allow_hyphen_values = true, default_value = "480x270", value_parser = parse_size)]
        size: (u32, u32),
        /// Relative standard error at which a technique's own reference counts as
        /// converged.
        #[arg(long, allow_negative_numbers = true, default_value_t = 0.02)]
        reference_noise: f64,
        /// Frame cap of a reference (1024x1024 photons per frame).
        #[arg(long, allow_negative_numbers = true, default_value_t = 256)]
        reference_frames: u32,
        /// Photons per light and batch of the light tracer (the default 16 x 4194304
        /// take about 13 s for `sphere` at 480x270 on two cores; cached).
        #[arg(long, allow_negative_numbers = true, default_value_t = 1 << 22)]
        tracer_photons: u64,
        /// Independent batches of the light tracer (its error bar is their spread; at
        /// least 2).
        #[arg(long, allow_negative_numbers = true, default_value_t = 16)]
        tracer_batches: u32,
        /// Spheres in the light tracer: the exact sphere (analytic) or the scene's
        /// tessellated mesh the techniques trace (mesh).
        #[arg(long, default_value = "analytic", value_parser = ["analytic", "mesh"])]
        tracer_spheres: String,
        /// What a silhouette pixel measures in the light tracer's image: centre-surface
        /// (default), the radiance of the surface the pixel's centre sees, every photon on
        /// it counted, hidden from the eye or not, as the caustic techniques' store test
        /// counts them; eye-visible, the flux the eye sees through the pixel's footprint
        /// (hidden photons dropped). The two differ only in pixels that straddle a
        /// silhouette.
        #[arg(long, default_value = "centre-surface", value_parser = ["centre-surface", "eye-visible"])]
        silhouette: String,
        /// Reference cache directory (default: OUT/references).
        #[arg(long)]
        cache: Option<PathBuf>,
        /// Comma-separated caustic filters to compare (Sspm's `filter` setting: density,
        /// bilateral; CausticMap's `gather`: box, density); each technique runs those it
        /// has, or its default where it has none of them.
        #[arg(long, default_value = "density")]
        filters: String,
        /// Settings file every combination starts from (JSON object of the technique's
        /// settings fields); the budget and the filter are set over it.
        #[arg(long)]
        settings: Option<PathBuf>,
        /// Output directory.
        #[arg(long, default_value = "report")]
        out: PathBuf,
    },
}

/// A settings file: a JSON object of a technique's settings fields (none: empty).
fn read_settings(
    path: Option<&std::path::Path>,
) -> Result<serde_json::Map<String, serde_json::Value>, String> {
    let Some(p) = path else {
        return Ok(serde_json::Map::new());
    };
    let f = std::fs::File::open(p).map_err(|e| format!("{}: {e}", p.display()))?;
    let mut text = String::new();
    std::io::Read::read_to_string(
        &mut std::io::Read::take(f, MAX_SETTINGS_FILE_BYTES + 1),
        &mut text,
    )
    .map_err(|e| format!("{}: {e}", p.display()))?;
    if text.len() as u64 > MAX_SETTINGS_FILE_BYTES {
        return Err(format!(
            "{}: larger than the {} MiB a settings file may have",
            p.display(),
            MAX_SETTINGS_FILE_BYTES >> 20
        ));
    }
    serde_json::from_str(&text).map_err(|e| format!("{}: {e}", p.display()))
}

/// Largest settings file read (bytes): 16 MiB, so that a pipe or /dev/zero is refused
/// after that many bytes, not after filling memory.
const MAX_SETTINGS_FILE_BYTES: u64 = 16 << 20;

fn parse_grid(s: &str) -> Result<(u32, u32), String> {
    let (a, b) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("'{s}' is not WxH (e.g. 1024x1024)"))?;
    let p = |t: &str| {
        t.trim().parse::<u32>().map_err(|e| match e.kind() {
            std::num::IntErrorKind::PosOverflow => {
                format!("'{s}': a side must be at most 4294967295")
            }
            _ => format!("'{s}' is not WxH with positive integers"),
        })
    };
    let (w, h) = (p(a)?, p(b)?);
    if w == 0 || h == 0 {
        return Err(format!("'{s}': both sizes must be at least 1"));
    }
    Ok((w, h))
}

/// `--size WxH`: a grid whose sides fit a camera (1..=16384 pixels, as the scene format's
/// `camera.width` and `camera.height`), so that the flag, not the camera, is named.
fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = parse_grid(s)?;
    if w > 16384 || h > 16384 {
        return Err(format!("'{s}': an image side must be at most 16384 pixels"));
    }
    Ok((w, h))
}

/// `--exposure`: a positive finite multiplier.
fn parse_exposure(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(x) if x > 0.0 && x.is_finite() => Ok(x),
        _ => Err(format!("'{s}' is not a positive finite number (f32)")),
    }
}

/// `--spheres`: analytic or mesh.
fn parse_spheres(
    flag: &str,
    s: &str,
) -> Result<caustica::reference::light_tracer::SphereModel, String> {
    use caustica::reference::light_tracer::SphereModel;
    match s {
        "analytic" => Ok(SphereModel::Analytic),
        "mesh" => Ok(SphereModel::Mesh),
        other => Err(format!("unknown {flag} '{other}': analytic or mesh")),
    }
}

fn main() -> ExitCode {
    let mut console = Console::new();
    let ran = match Cli::try_parse() {
        Ok(cli) => run(cli, &mut console),
        Err(e) => return usage(&e, &mut console),
    };
    finish(ran, &mut console)
}

/// The exit status of a command that ran: 0 when it succeeded or stdout's reader left
/// (see [`Stop::StdoutClosed`]), 1 with one line on stderr when it failed.
fn finish(ran: Result<(), Stop>, console: &mut Console) -> ExitCode {
    match ran.and_then(|()| console.flush()) {
        Ok(()) | Err(Stop::StdoutClosed) => ExitCode::SUCCESS,
        Err(Stop::Failed(e)) => {
            let _ = console.flush(); // what was printed before the error comes first
            note!("error: {}", e.replace('\n', " "));
            ExitCode::FAILURE
        }
    }
}

/// Arguments clap did not run: `--help`, `--version` and the help of a command without
/// its subcommand (clap's text, coloured on a terminal, with clap's status: 0, or 2 for
/// the missing subcommand), or a usage error (one line, status 2).
fn usage(e: &clap::Error, console: &mut Console) -> ExitCode {
    use clap::error::ErrorKind;
    let status = ExitCode::from(u8::try_from(e.exit_code()).unwrap_or(2));
    if matches!(
        e.kind(),
        ErrorKind::DisplayHelp
            | ErrorKind::DisplayVersion
            | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
    ) {
        let styled = e.render();
        if e.use_stderr() {
            let text = if std::io::stderr().is_terminal() {
                styled.ansi().to_string()
            } else {
                styled.to_string()
            };
            let _ = std::io::stderr().lock().write_all(text.as_bytes()); // as note_line
            return status;
        }
        let text = if std::io::stdout().is_terminal() {
            styled.ansi().to_string()
        } else {
            styled.to_string()
        };
        return match console
            .write(format_args!("{text}"))
            .and_then(|()| console.flush())
        {
            Ok(()) | Err(Stop::StdoutClosed) => status,
            Err(stop) => finish(Err(stop), console),
        };
    }
    let text = e.to_string();
    let first = text
        .lines()
        .next()
        .unwrap_or("bad arguments")
        .trim_start_matches("error: ");
    // clap's list of the values a flag takes is on a later line of its text: kept here
    let valid = match e.get(clap::error::ContextKind::ValidValue) {
        Some(clap::error::ContextValue::Strings(v)) if !v.is_empty() => {
            format!("; possible values: {}", v.join(", "))
        }
        _ => String::new(),
    };
    note!("error: {first}{valid} (see caustica --help)");
    ExitCode::from(2)
}

fn load_scene(arg: &str) -> Result<Scene, String> {
    if let Some(s) = builtin::builtin(arg) {
        return Ok(s);
    }
    let path = Path::new(arg);
    if path.exists() {
        let loaded = caustica::scene_file::load_scene_file(path).map_err(|e| e.to_string())?;
        for w in &loaded.warnings {
            note!("warning: {w}");
        }
        return Ok(loaded.scene);
    }
    Err(format!(
        "unknown scene '{arg}': not a built-in scene ({}) and no such file",
        builtin::BUILTIN_SCENES.join(", ")
    ))
}

fn run(cli: Cli, console: &mut Console) -> Result<(), Stop> {
    match cli.command {
        Command::Scenes {
            export: Some(name),
            format: fmt,
        } => {
            let s = builtin::builtin(&name).ok_or_else(|| {
                format!(
                    "unknown scene '{name}'; built-in scenes: {}",
                    builtin::BUILTIN_SCENES.join(", ")
                )
            })?;
            match fmt.as_str() {
                "json" => outln!(console, "{}", format::to_json(&s)),
                "gltf" => outln!(console, "{}", caustica::gltf_scene::scene_to_gltf(&s)),
                other => Err(format!("unknown --format '{other}': json or gltf").into()),
            }
        }
        Command::Scenes { export: None, .. } => {
            for name in builtin::BUILTIN_SCENES {
                let s = builtin::builtin(name).expect("listed scene exists");
                outln!(console, "{name:<12} {}", s.description)?;
            }
            Ok(())
        }
        Command::Backends => {
            for b in caustica::backend_statuses() {
                match b.available {
                    Ok((dev, t)) => outln!(
                        console,
                        "{:<8} available    {:<24} {dev}",
                        b.name,
                        t.label()
                    )?,
                    Err(why) => outln!(console, "{:<8} unavailable  {why}", b.name)?,
                }
            }
            let order: Vec<String> = caustica::auto_order()
                .iter()
                .map(|(n, t)| format!("{n} ({})", t.label()))
                .collect();
            outln!(
                console,
                "auto prefers: {} (hardware GPU, then the native CPU backend, then GPU APIs \
                 emulated on the CPU)",
                if order.is_empty() {
                    "nothing: no backend opens".to_string()
                } else {
                    order.join(" > ")
                }
            )
        }
        Command::Techniques => {
            let width = TECHNIQUES.iter().map(|t| t.name.len()).max().unwrap_or(0);
            for t in TECHNIQUES {
                outln!(console, "{:<width$} {}", t.name, t.title)?;
            }
            Ok(())
        }
        Command::Reference {
            scene,
            size,
            photons,
            batches,
            seed,
            spheres,
            silhouette,
            cache,
        } => {
            use caustica::reference::light_tracer::{load_or_compute, LightTracerSpec};
            let spheres = parse_spheres("--spheres", &spheres)?;
            let silhouette = silhouette
                .parse()
                .map_err(|e| format!("--silhouette: {e}"))?;
            if batches < 2 || photons == 0 {
                return Err("--batches must be at least 2 and --photons positive".into());
            }
            let scene = load_scene(&scene)?;
            let spec = LightTracerSpec {
                width: size.0,
                height: size.1,
                photons,
                batches,
                seed,
                spheres,
                silhouette,
                ..LightTracerSpec::default()
            };
            let (_, info) = load_or_compute(&cache, &scene, &spec, &mut |k, n, noise| {
                if noise.is_finite() {
                    note!("batch {k}/{n}: relative standard error {noise:.5}")
                } else {
                    // one batch has no spread
                    note!("batch {k}/{n}: relative standard error n/a (needs 2 batches)")
                }
            })
            .map_err(String::from)?;
            outln!(
                console,
                "{}",
                serde_json::to_string_pretty(&info).map_err(|e| e.to_string())?
            )
        }
        Command::Report {
            scenes,
            techniques,
            backends,
            budgets,
            repeats,
            frames,
            size,
            reference_noise,
            reference_frames,
            tracer_photons,
            tracer_batches,
            tracer_spheres,
            silhouette,
            cache,
            filters,
            settings,
            out,
        } => {
            let list = |s: &str| -> Vec<String> {
                s.split(',')
                    .map(|t| t.trim().to_string())
                    .filter(|t| !t.is_empty())
                    .collect()
            };
            let plan = caustica::report::ReportPlan {
                scenes: list(&scenes)
                    .iter()
                    .map(|s| load_scene(s))
                    .collect::<Result<_, _>>()?,
                techniques: list(&techniques),
                backends: list(&backends),
                budgets: list(&budgets)
                    .iter()
                    .map(|b| parse_grid(b).map_err(|e| format!("--budgets: {e}")))
                    .collect::<Result<_, _>>()?,
                frames: list(&frames)
                    .iter()
                    .map(|f| match f.parse::<usize>() {
                        Ok(n) if n >= 1 => Ok(n),
                        _ => Err(format!("--frames: '{f}' is not a count of at least 1")),
                    })
                    .collect::<Result<_, _>>()?,
                filters: list(&filters),
                settings: read_settings(settings.as_deref())?,
                repeats,
                reference: caustica::reference::ReferenceSpec {
                    width: size.0,
                    height: size.1,
                    target_noise: reference_noise,
                    max_frames: reference_frames,
                    ..Default::default()
                },
                tracer: caustica::reference::light_tracer::LightTracerSpec {
                    width: size.0,
                    height: size.1,
                    photons: tracer_photons,
                    batches: tracer_batches,
                    spheres: parse_spheres("--tracer-spheres", &tracer_spheres)?,
                    silhouette: silhouette
                        .parse()
                        .map_err(|e| format!("--silhouette: {e}"))?,
                    ..Default::default()
                },
            };
            if tracer_batches < 2 || tracer_photons == 0 {
                return Err(
                    "--tracer-batches must be at least 2 and --tracer-photons positive".into(),
                );
            }
            if !(reference_noise > 0.0 && reference_noise < 1.0) {
                return Err("--reference-noise must be in (0, 1)".into());
            }
            // everything that can be checked is checked before any reference is rendered
            if plan.filters.is_empty() {
                return Err("--filters lists nothing".into());
            }
            if repeats == 0 {
                return Err("--repeats must be at least 1".into());
            }
            caustica::report::validate(&plan).map_err(String::from)?;
            for b in &plan.backends {
                open_backend(b).map_err(|e| e.to_string())?;
            }
            caustica::output::prepare_output_dir(&out)?;
            let cache = cache.unwrap_or_else(|| out.join("references"));
            let records = caustica::report::run(&plan, &cache, &mut |line| note!("{line}"))
                .map_err(String::from)?;
            // the files first, the table last: a closed stdout loses only the table
            let path = out.join("report.json");
            caustica::output::write_file(
                &path,
                serde_json::to_string_pretty(&records)
                    .map_err(|e| e.to_string())?
                    .as_bytes(),
            )?;
            let mut written = vec![path.clone()];
            for scene in &plan.scenes {
                let png = out.join(format!(
                    "error_vs_time_{}.png",
                    caustica::output::file_stem(&scene.name)
                ));
                match caustica::report::plot(&records, &scene.name, &png) {
                    Ok(()) => {
                        note!("wrote {}", png.display());
                        written.push(png);
                    }
                    Err(e) => note!("no plot for {}: {e}", scene.name),
                }
            }
            note!("wrote {}", path.display());
            note_files_not_written(&out, &written);
            console.write(format_args!("{}", caustica::report::table(&records)))
        }
        Command::Render {
            scene,
            technique,
            backend,
            photons,
            size,
            seed,
            exposure,
            settings,
            filter,
            frames,
            animate,
            out,
        } => {
            if !technique_names().contains(&technique.as_str()) {
                return Err(format!(
                    "unknown technique '{technique}'; available: {}",
                    technique_names().join(", ")
                )
                .into());
            }
            let scene_arg = scene;
            let mut scene = load_scene(&scene_arg)?;
            if let Some((w, h)) = size {
                scene.camera.width = w;
                scene.camera.height = h;
            }
            let mut s = read_settings(settings.as_deref())?;
            if let Some(f) = filter {
                // the setting under the file's settings (AdaptiveCaustics': its deposit's)
                let setting = TECHNIQUES
                    .iter()
                    .find(|t| t.name == technique)
                    .and_then(|t| (t.filter_setting)(&s));
                match setting {
                    Some((key, values)) if values.contains(&f.as_str()) => {
                        put_setting(&mut s, key, f.into());
                    }
                    Some((_, values)) => {
                        return Err(format!(
                            "--filter {f}: {technique}'s filters are {}",
                            values.join(", ")
                        )
                        .into())
                    }
                    None => return Err(format!("--filter: {technique} has one filter").into()),
                }
            }
            // the flag overrides the settings file; neither: 1024x1024
            let (pw, ph) = photons.unwrap_or((1024, 1024));
            for (path, v) in [("frame.photons_w", pw), ("frame.photons_h", ph)] {
                if photons.is_some() || get_setting(&s, path).is_none() {
                    put_setting(&mut s, path, v.into());
                }
            }
            if let Some(seed) = seed {
                put_setting(&mut s, "frame.seed", seed.into());
            }
            // the height fields that --animate moves, each made an instance
            let mut animated = Vec::new();
            if let Some(dt) = animate {
                if !dt.is_finite() {
                    return Err("--animate must be a finite number of seconds".into());
                }
                if !(dt * (frames - 1) as f32).is_finite() {
                    return Err(format!(
                        "--animate: {frames} frames {dt} s apart end beyond a finite time \
                         in seconds (f32)"
                    )
                    .into());
                }
                for (k, o) in scene.objects.iter_mut().enumerate() {
                    if matches!(o.shape, caustica::scene::Shape::HeightField { .. }) {
                        o.transform
                            .get_or_insert(caustica::scene::Transform::IDENTITY);
                        animated.push(k);
                    }
                }
                if animated.is_empty() {
                    return Err(format!(
                        "--animate: scene '{}' has no height field to animate",
                        scene.name
                    )
                    .into());
                }
                if get_setting(&s, "frame.accumulate").is_none() {
                    put_setting(&mut s, "frame.accumulate", false.into());
                }
            }
            let defaults = TECHNIQUES
                .iter()
                .find(|t| t.name == technique)
                .map(|t| (t.default_settings)());
            // several frames accumulate unless the settings say otherwise
            if frames > 1 && get_setting(&s, "frame.accumulate").is_none() {
                put_setting(&mut s, "frame.accumulate", true.into());
            }
            let accumulates = get_setting(&s, "frame.accumulate")
                .and_then(|v| v.as_bool())
                .unwrap_or(false);
            let base_seed = get_setting(&s, "frame.seed")
                .or_else(|| defaults.as_ref().and_then(|d| d["frame"].get("seed")))
                .and_then(|v| v.as_u64())
                .unwrap_or(0) as u32;
            let stem = caustica::output::file_stem(&scene.name);
            let mut be = open_backend(&backend).map_err(|e| e.to_string())?;
            let asked = get_setting(&s, "frame.outputs").cloned();
            let mut t = create(
                &technique,
                be.as_mut(),
                &scene,
                &serde_json::Value::Object(s),
            )
            .map_err(|e| match e {
                // what only a technique checks (its receivers' UVs, the lights' flux bound)
                caustica::Error::InvalidScene(_) => format!("{scene_arg}: {e}"),
                e => e.to_string(),
            })?;
            // the folder made once the technique is (no empty folder from a failed start)
            let made_here = !out.exists();
            if let Err(e) = caustica::output::prepare_output_dir(&out) {
                let _ = t.free(be.as_mut());
                return Err(e.into());
            }
            // a list of outputs may name some another technique has (settings shared
            // between techniques): say which are not written
            if let Some(serde_json::Value::Array(asked)) = asked {
                let own: Vec<&str> = t.outputs().iter().map(|o| o.name).collect();
                let other: Vec<&str> = asked
                    .iter()
                    .filter_map(|v| v.as_str())
                    .filter(|a| !own.contains(a))
                    .collect();
                if !other.is_empty() {
                    note!(
                        "warning: {technique} has no {} output ({} are its own); not written",
                        other.join(", "),
                        own.join(", ")
                    );
                }
            }
            // the files this run writes in `out`, for the warning about the others
            let mut written = Vec::new();
            // the technique is freed whether its frames and images worked or not
            let bar = ProgressBar::new(0);
            bar.set_style(
                ProgressStyle::with_template(
                    "{spinner} {msg}photons {human_pos}/{human_len} [{bar:30}] {eta}",
                )
                .expect("valid template")
                .progress_chars("=> "),
            );
            // the spinner turns through passes that trace no photons (a large image's
            // G-buffer, the images' files)
            bar.enable_steady_tick(std::time::Duration::from_millis(200));
            let mut frames_and_images = || -> Result<FrameStats, String> {
                let mut stats = None;
                for f in 0..frames {
                    if frames > 1 {
                        bar.set_message(format!("frame {}/{frames}, ", f + 1));
                    }
                    if let (Some(dt), true) = (animate, f > 0) {
                        for &k in &animated {
                            let shape = scene.objects[k].shape.advanced(dt * f as f32);
                            let m = caustica::scene::shapes::tessellate(&shape);
                            t.set_object_vertices(be.as_mut(), k, &m.positions, &m.normals)
                                .map_err(|e| e.to_string())?;
                        }
                    } else if f > 0 && !accumulates {
                        t.set_seed(base_seed.wrapping_add(f));
                    }
                    stats = Some(
                        t.frame(be.as_mut(), &mut |p| {
                            bar.set_length(p.photons_total);
                            bar.set_position(p.photons_done);
                        })
                        .map_err(|e| e.to_string())?,
                    );
                    if animate.is_some() {
                        let img = t
                            .read_output(be.as_mut(), caustica::Output::Composite)
                            .map_err(|e| e.to_string())?;
                        let png = out.join(format!("{stem}_f{f:03}_composite.png"));
                        write_png(&png, &img, exposure)?;
                        written.push(png);
                    }
                }
                let stats = stats.expect("at least one frame");
                bar.set_message("writing the images, ");
                for output in t.outputs().into_iter().filter(|o| o.requested) {
                    let name = output.name;
                    let img = t
                        .read_output(be.as_mut(), output.output)
                        .map_err(|e| e.to_string())?;
                    let exr = out.join(format!("{stem}_{name}.exr"));
                    write_exr(&exr, &img)?;
                    written.push(exr);
                    if output.output == caustica::Output::Composite {
                        let png = out.join(format!("{stem}_composite.png"));
                        write_png(&png, &img, exposure)?;
                        written.push(png);
                    }
                }
                Ok(stats)
            };
            let rendered = frames_and_images();
            bar.finish_and_clear();
            let s = t.settings_json();
            let freed = t.free(be.as_mut()).map_err(|e| e.to_string());
            // a render that failed before writing a file leaves no folder it made
            if rendered.is_err() && made_here {
                let _ = std::fs::remove_dir(&out);
            }
            let stats = rendered?;
            freed?;
            let doc = serde_json::json!({ "scene": scene.name, "technique": technique, "settings": s, "stats": stats });
            let path = out.join("stats.json");
            caustica::output::write_file(
                &path,
                serde_json::to_string_pretty(&doc)
                    .map_err(|e| e.to_string())?
                    .as_bytes(),
            )?;
            written.push(path);
            note_files_not_written(&out, &written);
            outln!(
                console,
                "{}: {} photons emitted, {} stored, {} deposited; {:.1} ms; wrote {}",
                scene.name,
                stats.photons_emitted,
                stats.photons_stored,
                stats.photons_deposited,
                stats.frame_ms,
                out.display()
            )
        }
    }
}
