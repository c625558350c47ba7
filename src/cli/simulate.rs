//! `origami-fmu simulate`: run a scene with the plain Rust model (no FMU)
//! and write its outputs to CSV, pictures (GIF, snapshots, plot) and a
//! ParaView series. The input is the model's built-in ramp (`--ramp`), or
//! a CSV with a `time` column and one column per input, linearly interpolated.

use super::{CliError, InputCsvError};
use crate::model::Model;
use clap::Args;
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `simulate`.
#[derive(Args, Debug)]
pub struct SimulateArgs {
    /// The scene: a FOLD file (or a scene JSON).
    pub scene: PathBuf,
    /// Stop time in s (default: the scene's stop time, 1 s for a plain FOLD file). It does not
    /// change the input signal: a shorter run shows the beginning of the same fold.
    #[arg(long)]
    pub stop_time: Option<f64>,
    /// Output (communication) step in s.
    #[arg(long, default_value_t = 1e-2)]
    pub step: f64,
    /// The default input: every rest-angle actuator (`fold`) goes from 0 to 1 over SECONDS,
    /// then holds 1 (the FMU's parameter ramp.time); 0 leaves the actuators at their start
    /// values.
    #[arg(
        long,
        value_name = "SECONDS",
        default_value_t = 0.5,
        conflicts_with = "input"
    )]
    pub ramp: f64,
    /// Shape of the default ramp: linear, or smooth (zero slope at both ends).
    #[arg(
        long,
        value_name = "SHAPE",
        default_value = "linear",
        conflicts_with = "input"
    )]
    pub ramp_shape: RampShapeArg,
    /// Input CSV instead of the ramp: a `time` column and columns named after inputs, linearly
    /// interpolated (held before the first and after the last row).
    #[arg(long)]
    pub input: Option<PathBuf>,
    /// Output CSV: time and every output at every output step.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Animated GIF of the folding sheet (50 frames at most).
    #[arg(long, value_name = "FILE")]
    pub gif: Option<PathBuf>,
    /// PNG sheet of 3D views of the sheet at six evenly spaced times, on one scale.
    #[arg(long, value_name = "FILE")]
    pub snapshots: Option<PathBuf>,
    /// PNG plot of every fold angle and the energies against time.
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// Also write a ParaView time series into this folder: STEM.pvd and one
    /// STEM_NNNNN.vtu per output time (STEM = the scene file's name), with
    /// the model's mesh, per-facet strain energy and per-crease fold angle.
    #[arg(long, value_name = "DIR")]
    pub pvd: Option<PathBuf>,
    /// Write the motion as a multi-frame FOLD file: the crease pattern (in metres) and one frame
    /// per output step with the simulated vertices_coords and edges_foldAngle (Rabbit Ear,
    /// Origami Simulator and the FOLD library read it; read back here, its frames are the
    /// stages of a folding sequence). FOLD scenes only.
    #[arg(long, value_name = "FILE")]
    pub fold_out: Option<PathBuf>,
    /// How a FOLD scene is read (--frame, --size, --unit, --f-edges).
    #[command(flatten)]
    pub read: super::SceneOptions,
}

/// `--ramp-shape`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum RampShapeArg {
    /// Straight from 0 to 1.
    Linear,
    /// Smoothstep: zero slope at both ends.
    Smooth,
}

/// Most communication steps (output rows) of one run.
const MAX_STEPS: usize = 10_000_000;

/// Input signals: times and, per model input index, values.
struct Signals {
    time: Vec<f64>,
    columns: Vec<(usize, Vec<f64>)>,
}

impl Signals {
    fn at(&self, t: f64) -> Vec<(usize, f64)> {
        let k = self.time.partition_point(|&x| x <= t);
        self.columns
            .iter()
            .map(|(i, v)| {
                let val = if k == 0 {
                    v[0]
                } else if k >= self.time.len() {
                    v[v.len() - 1]
                } else {
                    let (t0, t1) = (self.time[k - 1], self.time[k]);
                    v[k - 1] + (v[k] - v[k - 1]) * (t - t0) / (t1 - t0)
                };
                (*i, val)
            })
            .collect()
    }
}

fn read_inputs(path: &PathBuf, model: &Model) -> Result<Signals, CliError> {
    let text = std::fs::read_to_string(path).map_err(super::error::io("read", path))?;
    let mut lines = text.lines().filter(|l| !l.trim().is_empty());
    let header: Vec<&str> = lines
        .next()
        .ok_or(InputCsvError::Empty)?
        .split(',')
        .map(str::trim)
        .collect();
    let tcol = header
        .iter()
        .position(|h| *h == "time")
        .ok_or(InputCsvError::NoTimeColumn)?;
    let mut cols = Vec::new();
    for (c, h) in header.iter().enumerate() {
        if c == tcol {
            continue;
        }
        let i = model
            .inputs()
            .iter()
            .position(|v| v.name == *h)
            .ok_or_else(|| InputCsvError::UnknownColumn(h.to_string()))?;
        cols.push((c, i));
    }
    let mut time = Vec::new();
    let mut values = vec![Vec::new(); cols.len()];
    for (n, line) in lines.enumerate() {
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        let (line, column) = (n + 2, |c: usize| c + 1);
        let num = |c: usize| -> Result<f64, InputCsvError> {
            let x: f64 = f
                .get(c)
                .ok_or(InputCsvError::MissingColumn {
                    line,
                    column: column(c),
                })?
                .parse()
                .map_err(|_| InputCsvError::NotANumber {
                    line,
                    column: column(c),
                })?;
            if x.is_finite() {
                Ok(x)
            } else {
                Err(InputCsvError::NonFinite { line })
            }
        };
        let t = num(tcol)?;
        if time.last().is_some_and(|&p| t <= p) {
            return Err(InputCsvError::TimeNotIncreasing { line }.into());
        }
        time.push(t);
        for (k, &(c, _)) in cols.iter().enumerate() {
            values[k].push(num(c)?);
        }
    }
    if time.is_empty() {
        return Err(InputCsvError::NoRows.into());
    }
    Ok(Signals {
        time,
        columns: cols.iter().map(|&(_, i)| i).zip(values).collect(),
    })
}

/// Set a parameter of `model` by name (a scene may not have it).
fn set_parameter(model: &mut Model, name: &str, value: f64) -> Result<bool, CliError> {
    match model.parameter_id(name) {
        Some(i) => {
            model.set_parameter(i, value)?;
            Ok(true)
        }
        None => Ok(false),
    }
}

/// What a run writes besides the CSV: pictures from recorded frames.
struct Pictures {
    sheet: crate::pictures::Sheet,
    /// Output rows to record as frames (GIF and snapshots).
    gif_rows: Vec<usize>,
    snapshot_rows: Vec<usize>,
    /// Recorded frames by output row.
    frames: Vec<(usize, crate::pictures::Frame)>,
    series: crate::pictures::Series,
}

impl Pictures {
    /// What `--gif`, `--snapshots` and `--plot` ask to record over `n`
    /// communication steps (None: no pictures).
    fn for_args(args: &SimulateArgs, model: &Model, n: usize) -> Option<Pictures> {
        let rows = |on: bool, count| {
            if on {
                crate::pictures::frame_rows(n + 1, count)
            } else {
                vec![]
            }
        };
        (args.gif.is_some() || args.snapshots.is_some() || args.plot.is_some()).then(|| Pictures {
            sheet: crate::pictures::Sheet::new(model),
            gif_rows: rows(args.gif.is_some(), 50),
            snapshot_rows: rows(args.snapshots.is_some(), 6),
            frames: Vec::new(),
            series: Default::default(),
        })
    }

    fn record(&mut self, row: usize, model: &Model, values: &[f64]) {
        if self.gif_rows.contains(&row) || self.snapshot_rows.contains(&row) {
            self.frames.push((row, self.sheet.frame(model, values)));
        }
        self.series.push(&self.sheet, model.time(), values);
    }

    /// Write the pictures asked for, from what was recorded.
    fn write(&self, args: &SimulateArgs, title: &str) -> Result<(), CliError> {
        let pick = |rows: &[usize]| -> Vec<&crate::pictures::Frame> {
            self.frames
                .iter()
                .filter(|(r, _)| rows.contains(r))
                .map(|(_, f)| f)
                .collect()
        };
        if let Some(p) = &args.gif {
            let frames = pick(&self.gif_rows);
            crate::pictures::write_gif(p, &self.sheet, &frames, title)?;
            super::err(&format!(
                "animation: {} frames -> {}\n",
                frames.len(),
                p.display()
            ));
        }
        if let Some(p) = &args.snapshots {
            let frames = pick(&self.snapshot_rows);
            crate::pictures::write_snapshots(
                p,
                &self.sheet,
                &frames,
                &format!("{title}: folding"),
            )?;
            super::err(&format!(
                "snapshots: {} views -> {}\n",
                frames.len(),
                p.display()
            ));
        }
        if let Some(p) = &args.plot {
            crate::pictures::write_plot(p, &self.sheet, &self.series, title)?;
            super::err(&format!("plot -> {}\n", p.display()));
        }
        Ok(())
    }
}

/// The progress bar of a run: hidden for its first second and whenever
/// standard error is not a terminal (CI logs stay clean).
struct Progress {
    bar: indicatif::ProgressBar,
    started: std::time::Instant,
    shown: bool,
    stop: f64,
}

impl Progress {
    fn new(steps: usize, stop: f64) -> Progress {
        let bar = indicatif::ProgressBar::with_draw_target(
            Some(steps as u64),
            indicatif::ProgressDrawTarget::hidden(),
        );
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} [{bar:28}] {msg}  {elapsed} elapsed, ~{eta} left",
            )
            .expect("valid template")
            .progress_chars("=> "),
        );
        Progress {
            bar,
            started: std::time::Instant::now(),
            shown: false,
            stop,
        }
    }

    fn update(&mut self, k: usize, t: f64, steps: usize, stage: Option<String>) {
        if !self.shown && self.started.elapsed().as_secs_f64() > 1.0 {
            self.shown = true;
            self.bar
                .set_draw_target(indicatif::ProgressDrawTarget::stderr_with_hz(4));
            self.bar
                .enable_steady_tick(std::time::Duration::from_millis(250));
        }
        let wall = self.started.elapsed().as_secs_f64().max(1e-9);
        let stage = stage.map(|s| format!("{s}, ")).unwrap_or_default();
        self.bar.set_message(format!(
            "t = {t:.3} / {} s, {stage}{steps} internal steps, {:.3} simulated s per s",
            self.stop,
            t / wall
        ));
        self.bar.set_position(k as u64);
    }

    fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

/// Run `simulate`.
pub fn run(args: &SimulateArgs) -> Result<(), CliError> {
    // The closing report gives the stepper's phase times.
    crate::solver::set_phase_timing(true);
    let loaded = super::load_scene(&args.scene, &args.read)?;
    for n in &loaded.notes {
        super::err(&format!("{n}\n"));
    }
    let scene = loaded.scene;
    let stop = args.stop_time.unwrap_or(scene.solver.stop_time);
    check_times(args, stop)?;
    let title = scene.name.clone();
    let mut model = Model::new(scene)?;
    let signals = choose_signals(args, &mut model)?;
    if let Some(sig) = &signals {
        for (i, v) in sig.at(0.0) {
            model.set_input(crate::model::InputId(i), v)?;
        }
    }
    model.initialize()?;
    let mut csv = args
        .output
        .as_ref()
        .map(|path| Csv::create(path, &model))
        .transpose()?;
    let n = (stop / args.step).round().max(1.0) as usize;
    let mut pictures = Pictures::for_args(args, &model, n);
    let values = model.output_values();
    if let Some(c) = csv.as_mut() {
        c.row(0.0, &values)?;
    }
    if let Some(p) = pictures.as_mut() {
        p.record(0, &model, &values);
    }
    let mut series = pvd_series(args, &model)?;
    let mut motion = motion(args, &model)?;
    if let Some(m) = motion.as_mut() {
        m.record(&model);
    }
    let clock = crate::cpu_time::Stopwatch::start();
    let mut progress = Progress::new(n, stop);
    let mut total = crate::model::StepReport::default();
    let mut failure = None;
    for k in 1..=n {
        let t = (k as f64 * args.step).min(stop);
        if let Some(sig) = &signals {
            set_signals(&mut model, sig, t)?;
        }
        match model.advance(t - model.time()) {
            Ok(r) => total.accumulate(&r),
            Err(e) => {
                failure = Some(e);
                break;
            }
        }
        let values = model.output_values();
        if let Some(c) = csv.as_mut() {
            c.row(t, &values)?;
        }
        if let Some(p) = pictures.as_mut() {
            p.record(k, &model, &values);
        }
        if let Some(s) = series.as_mut() {
            s.write(&model)?;
        }
        if let Some(m) = motion.as_mut() {
            m.record(&model);
        }
        progress.update(k, t, total.steps, stage(&model));
    }
    progress.finish();
    if let (Some(m), Some(path)) = (&motion, &args.fold_out) {
        m.write(path).map_err(super::error::io("write", path))?;
        super::err(&format!(
            "motion: {} frames -> {}\n",
            m.len(),
            path.display()
        ));
    }
    if let Some(s) = stage(&model) {
        super::err(&format!("sequence: {s} at t = {} s\n", model.time()));
    }
    let (cpu, wall) = (clock.cpu(), clock.wall());
    if let Some(c) = csv.as_mut() {
        c.flush()?;
    }
    if let Some(s) = &series {
        super::err(&format!("ParaView series -> {}\n", s.finish()?.display()));
    }
    if let Some(p) = &pictures {
        p.write(args, &title)?;
    }
    let reached = model.time();
    let to = args
        .output
        .as_ref()
        .map(|p| format!(" -> {}", p.display()))
        .unwrap_or_default();
    super::err(&format!(
        "simulated {reached} s in {cpu:.2} s of CPU ({wall:.2} s wall){to}\n"
    ));
    super::err(&closing_report(&total));
    match failure {
        None => Ok(()),
        Some(source) => Err(CliError::RunStopped {
            source,
            reached,
            stop,
        }),
    }
}

/// Where the scene's folding sequence is now ("stage 2/5 (petals), 40 %").
fn stage(model: &Model) -> Option<String> {
    let sq = model.scene().sequence.as_ref()?;
    Some(sq.describe(model.sequence_position()?))
}

/// The motion recorder of `--fold-out`, over the FOLD frame the scene was
/// read from (a scene JSON has none: refused).
fn motion(args: &SimulateArgs, model: &Model) -> Result<Option<crate::motion::Motion>, CliError> {
    let Some(out) = &args.fold_out else {
        return Ok(None);
    };
    if args.scene.extension().is_some_and(|e| e == "json") {
        return Err(CliError::FoldOutNeedsFold(out.clone()));
    }
    let text =
        std::fs::read_to_string(&args.scene).map_err(super::error::io("read", &args.scene))?;
    let frame = args
        .read
        .frame
        .as_deref()
        .map(|f| f.parse().expect("infallible"));
    let (cp, _) =
        crate::scene::fold::parse(&text, frame.as_ref()).map_err(|source| CliError::Scene {
            path: args.scene.clone(),
            source,
        })?;
    Ok(Some(crate::motion::Motion::new(&cp, model)))
}

/// The communication step, the stop time and the ramp are usable.
fn check_times(args: &SimulateArgs, stop: f64) -> Result<(), CliError> {
    if !(args.step > 0.0 && args.step.is_finite() && stop > 0.0 && stop.is_finite()) {
        return Err(CliError::StepOrStopTime);
    }
    if stop / args.step > MAX_STEPS as f64 {
        return Err(CliError::TooManySteps {
            steps: (stop / args.step).round(),
            max: MAX_STEPS,
        });
    }
    if !(args.ramp >= 0.0 && args.ramp.is_finite()) {
        return Err(CliError::RampTime);
    }
    Ok(())
}

/// The input table of `--input`, or else the model's built-in ramp (the
/// FMU's ramp.time: the same signal whatever the stop time), said on stderr.
fn choose_signals(args: &SimulateArgs, model: &mut Model) -> Result<Option<Signals>, CliError> {
    if let Some(p) = &args.input {
        return Ok(Some(read_inputs(p, model)?));
    }
    let shape = match args.ramp_shape {
        RampShapeArg::Linear => 0.0,
        RampShapeArg::Smooth => 1.0,
    };
    let has = set_parameter(model, "ramp.time", args.ramp)?;
    set_parameter(model, "ramp.shape", shape)?;
    if has && args.ramp > 0.0 {
        let walks = model
            .scene()
            .sequence
            .as_ref()
            .map(|sq| {
                format!(
                    "; the fold input walks the {} stage(s) of the folding sequence",
                    sq.stages.len()
                )
            })
            .unwrap_or_default();
        super::err(&format!(
            "input: every rest-angle actuator ramps from 0 to 1 over {} s ({}), then holds 1{walks}\n",
            args.ramp,
            if shape == 0.0 { "linear" } else { "smooth" }
        ));
    } else if !has {
        super::err(
            "input: the scene has no rest-angle actuator; inputs stay at their start values\n",
        );
    }
    Ok(None)
}

/// The table's value at the step start and its slope over the step to `t`
/// (the FMU's held input plus derivative): the piecewise linear signal
/// itself, never a staircase.
fn set_signals(model: &mut Model, sig: &Signals, t: f64) -> Result<(), CliError> {
    let t0 = model.time();
    let h = t - t0;
    for ((i, v0), (_, v1)) in sig.at(t0).into_iter().zip(sig.at(t)) {
        let i = crate::model::InputId(i);
        model.set_input(i, v0)?;
        model.set_input_derivative(i, 1, (v1 - v0) / h)?;
    }
    Ok(())
}

/// The CSV of `--output`: a header of the output names, a row per
/// communication point.
struct Csv<'a> {
    out: std::io::BufWriter<std::fs::File>,
    path: &'a PathBuf,
}

impl<'a> Csv<'a> {
    fn create(path: &'a PathBuf, model: &Model) -> Result<Self, CliError> {
        let file = std::fs::File::create(path).map_err(super::error::io("write", path))?;
        let mut csv = Csv {
            out: std::io::BufWriter::new(file),
            path,
        };
        let names: Vec<&str> = model.outputs().iter().map(|v| v.name.as_str()).collect();
        let header = format!("time,{}", names.join(","));
        csv.line(&header)?;
        Ok(csv)
    }

    fn line(&mut self, line: &str) -> Result<(), CliError> {
        writeln!(self.out, "{line}").map_err(super::error::io("write", self.path))
    }

    fn row(&mut self, t: f64, vals: &[f64]) -> Result<(), CliError> {
        let mut line = format!("{t}");
        for v in vals {
            line.push_str(&format!(",{v}"));
        }
        self.line(&line)
    }

    fn flush(&mut self) -> Result<(), CliError> {
        self.out
            .flush()
            .map_err(super::error::io("write", self.path))
    }
}

/// The ParaView series of `--pvd`, its first frame written.
fn pvd_series(
    args: &SimulateArgs,
    model: &Model,
) -> Result<Option<crate::paraview::Series>, CliError> {
    let Some(dir) = &args.pvd else {
        return Ok(None);
    };
    let stem = args
        .scene
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    let mut s = crate::paraview::Series::new(dir, &stem, model)?;
    s.write(model)?;
    Ok(Some(s))
}

/// The stepper's work over the run, a line for stderr.
fn closing_report(total: &crate::model::StepReport) -> String {
    format!(
        "{} internal steps ({} rejected, smallest {:.3e} s), {} Newton iterations, \
         {} factorizations; CPU in assembly {:.2} s, factorization {:.2} s, solves {:.2} s\n",
        total.steps,
        total.rejected,
        total.min_step,
        total.newton_iterations,
        total.factorizations,
        total.assembly_time,
        total.factor_time,
        total.solve_time
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Past its first second the bar draws to standard error, but only to
    /// a terminal: under `cargo test` (and in CI logs, pipes) it stays hidden.
    #[test]
    fn progress_is_hidden_off_a_terminal() {
        use std::io::IsTerminal;
        let mut p = Progress::new(10, 1.0);
        p.started -= std::time::Duration::from_secs(2);
        p.update(5, 0.5, 42, Some("stage 1/2, 50 %".into()));
        assert!(p.shown);
        assert_eq!(p.bar.is_hidden(), !std::io::stderr().is_terminal());
        p.finish();
    }
}
