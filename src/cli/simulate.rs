//! `origami-fmu simulate`: run a scene with the plain Rust model (no FMU)
//! and write every output to CSV. Inputs come from an optional CSV with a
//! `time` column and one column per input name, linearly interpolated.

use crate::model::Model;
use clap::Args;
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `simulate`.
#[derive(Args, Debug)]
pub struct SimulateArgs {
    /// Scene file (FOLD, or a scene JSON).
    pub scene: PathBuf,
    /// Stop time in s (default: the scene's stop time).
    #[arg(long)]
    pub stop_time: Option<f64>,
    /// Output (communication) step in s.
    #[arg(long, default_value_t = 1e-2)]
    pub step: f64,
    /// Input CSV: a `time` column and columns named after inputs. Without
    /// it every rest-angle actuator ramps from 0 to 1 over the first half.
    #[arg(long)]
    pub input: Option<PathBuf>,
    /// Output CSV.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Also write a ParaView time series into this folder: STEM.pvd and one
    /// STEM_NNNNN.vtu per output time (STEM = the scene file's name), with
    /// the model's mesh, per-facet strain energy and per-crease fold angle.
    #[arg(long, value_name = "DIR")]
    pub pvd: Option<PathBuf>,
}

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

fn read_inputs(path: &PathBuf, model: &Model) -> Result<Signals, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let mut lines = text.lines().filter(|l| !l.trim().is_empty());
    let header: Vec<&str> = lines
        .next()
        .ok_or("input CSV is empty")?
        .split(',')
        .map(str::trim)
        .collect();
    let tcol = header
        .iter()
        .position(|h| *h == "time")
        .ok_or("input CSV has no `time` column")?;
    let mut cols = Vec::new();
    for (c, h) in header.iter().enumerate() {
        if c == tcol {
            continue;
        }
        let i = model
            .inputs()
            .iter()
            .position(|v| v.name == *h)
            .ok_or_else(|| format!("input CSV column `{h}` is not an input of the scene"))?;
        cols.push((c, i));
    }
    let mut time = Vec::new();
    let mut values = vec![Vec::new(); cols.len()];
    for (n, line) in lines.enumerate() {
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        let num = |c: usize| -> Result<f64, String> {
            let x: f64 = f
                .get(c)
                .ok_or_else(|| format!("input CSV line {}: missing column {}", n + 2, c + 1))?
                .parse()
                .map_err(|_| {
                    format!("input CSV line {}: column {} is not a number", n + 2, c + 1)
                })?;
            if x.is_finite() {
                Ok(x)
            } else {
                Err(format!("input CSV line {}: non-finite value", n + 2))
            }
        };
        let t = num(tcol)?;
        if time.last().is_some_and(|&p| t <= p) {
            return Err(format!("input CSV line {}: time must increase", n + 2));
        }
        time.push(t);
        for (k, &(c, _)) in cols.iter().enumerate() {
            values[k].push(num(c)?);
        }
    }
    if time.is_empty() {
        return Err("input CSV has no rows".into());
    }
    Ok(Signals {
        time,
        columns: cols.iter().map(|&(_, i)| i).zip(values).collect(),
    })
}

/// Run `simulate`.
pub fn run(args: &SimulateArgs) -> Result<(), String> {
    let scene = super::build::load_scene(&args.scene)?;
    let stop = args.stop_time.unwrap_or(scene.solver.stop_time);
    if !(args.step > 0.0 && args.step.is_finite() && stop > 0.0 && stop.is_finite()) {
        return Err("--step and --stop-time must be positive numbers".into());
    }
    let mut model = Model::new(scene).map_err(|e| e.to_string())?;
    let signals = match &args.input {
        Some(p) => read_inputs(p, &model)?,
        None => {
            let ramp: Vec<(usize, Vec<f64>)> = model
                .scene()
                .actuators
                .iter()
                .enumerate()
                .filter(|(_, a)| a.mode == crate::scene::ActuatorMode::RestAngle)
                .map(|(i, _)| (i, vec![0.0, 1.0]))
                .collect();
            Signals {
                time: vec![0.0, 0.5 * stop],
                columns: ramp,
            }
        }
    };
    for (i, v) in signals.at(0.0) {
        model.set_input(i, v).map_err(|e| e.to_string())?;
    }
    model.initialize().map_err(|e| e.to_string())?;
    let file = std::fs::File::create(&args.output)
        .map_err(|e| format!("cannot write {}: {e}", args.output.display()))?;
    let mut out = std::io::BufWriter::new(file);
    let names: Vec<&str> = model.outputs().iter().map(|v| v.name.as_str()).collect();
    let write_row = |out: &mut std::io::BufWriter<std::fs::File>, t: f64, vals: &[f64]| {
        let mut line = format!("{t}");
        for v in vals {
            line.push_str(&format!(",{v}"));
        }
        writeln!(out, "{line}")
    };
    let io = |e: std::io::Error| format!("cannot write {}: {e}", args.output.display());
    writeln!(out, "time,{}", names.join(",")).map_err(io)?;
    write_row(&mut out, 0.0, &model.output_values()).map_err(io)?;
    let mut series = match &args.pvd {
        Some(dir) => {
            let stem = args
                .scene
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "scene".into());
            let mut s = crate::paraview::Series::new(dir, &stem, &model)?;
            s.write(&model)?;
            Some(s)
        }
        None => None,
    };
    let n = (stop / args.step).round().max(1.0) as usize;
    let started = std::time::Instant::now();
    let mut last_report = started;
    let mut total = crate::model::StepReport::default();
    for k in 1..=n {
        let t = (k as f64 * args.step).min(stop);
        for (i, v) in signals.at(t) {
            model.set_input(i, v).map_err(|e| e.to_string())?;
        }
        let h = t - model.time();
        let r = model.advance(h).map_err(|e| e.to_string())?;
        total.accumulate(&r);
        let steps = total.steps;
        write_row(&mut out, t, &model.output_values()).map_err(io)?;
        if let Some(s) = series.as_mut() {
            s.write(&model)?;
        }
        if last_report.elapsed().as_secs_f64() > 2.0 {
            eprintln!(
                "t = {t:.4} / {stop} s ({:.0} %), {steps} internal steps",
                100.0 * t / stop
            );
            last_report = std::time::Instant::now();
        }
    }
    out.flush().map_err(io)?;
    if let Some(s) = &series {
        eprintln!("ParaView series -> {}", s.finish()?.display());
    }
    eprintln!(
        "simulated {stop} s in {:.2} s of CPU wall time -> {}",
        started.elapsed().as_secs_f64(),
        args.output.display()
    );
    eprintln!(
        "{} internal steps ({} rejected, smallest {:.3e} s), {} Newton iterations, \
         {} factorizations; assembly {:.2} s, factorization {:.2} s, solves {:.2} s",
        total.steps,
        total.rejected,
        total.min_step,
        total.newton_iterations,
        total.factorizations,
        total.assembly_time,
        total.factor_time,
        total.solve_time
    );
    Ok(())
}
