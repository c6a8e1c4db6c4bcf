//! `orbitlash environment`: the orbit's heat-flux environment as the commercial tools
//! report it: β, eclipses (entry, exit, length), the Sun's distance and flux, and a
//! time series (`--csv`) of the orbit angle, the sunlit fraction, β and each face's
//! incident solar, albedo and Earth-infrared flux.

use std::io::Write;
use std::path::PathBuf;

use anyhow::{Result, bail};
use clap::Args;

use orbitlash::io::atomic::{AtomicFile, OutputPolicy};
use orbitlash::orbit::faces::{Face, incident};
use orbitlash::orbit::{Environment, EnvironmentModel};

use super::table::{self, Align};
use super::{load_with, orbits_arg, print_out};

/// Validates `--step-s`: a positive, finite number of seconds.
fn step_arg(s: &str) -> Result<f64, String> {
    let v: f64 = s.parse().map_err(|_| format!("`{s}` is not a number"))?;
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(format!("the step must be > 0 s (got {s})"))
    }
}

/// The most rows `--csv` writes.
const MAX_ROWS: f64 = 1e7;
/// Eclipses listed one by one before the rest are summed up.
const LISTED_ECLIPSES: usize = 8;

#[derive(Args, Debug)]
pub struct EnvironmentArgs {
    /// Scenario file (TOML).
    scenario: PathBuf,
    /// Orbits to cover from the start.
    #[arg(long, value_parser = orbits_arg, default_value = "1")]
    orbits: f64,
    /// Interval between CSV rows, s (default: 1/360 of an orbit).
    #[arg(long, value_parser = step_arg)]
    step_s: Option<f64>,
    /// Write the time series here: time_s, utc (a dated scenario), orbit_angle_deg,
    /// sun_fraction (0 … 1 in a penumbra), beta_deg, solar_flux_w_per_m2 (the flux
    /// reaching the spacecraft, as in a run's log: 0 in the umbra, dimmed in a
    /// penumbra), solar_flux_unshadowed_w_per_m2 (at its distance from the Sun, before
    /// any shadow), and per face `<node>.<face>.solar_w_per_m2`, `.albedo_w_per_m2`,
    /// `.earth_ir_w_per_m2` (incident, before absorptivity).
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Draw each face's incident solar, albedo and Earth-infrared flux against time,
    /// eclipses shaded: `.png` or `.svg` (the series of `--csv`).
    #[arg(long, value_name = "FILE.png|svg")]
    plot: Option<PathBuf>,
    /// Change a number of the scenario by its key path (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    sets: Vec<String>,
}

pub fn environment(a: EnvironmentArgs) -> Result<()> {
    let loaded = load_with(Some(&a.scenario), &a.sets)?;
    // The outputs are checked before any work: never an input, a device, a link or
    // each other.
    let mut planned = orbitlash::io::output::Outputs::new(OutputPolicy::reading(&loaded.inputs()));
    if let Some(p) = &a.csv {
        planned.file("--csv", p)?;
    }
    if let Some(p) = &a.plot {
        super::plot::format_of(p, "--plot")?;
        planned.file("--plot", p)?;
    }
    let mut csv = match &a.csv {
        Some(p) => Some(AtomicFile::create(
            p,
            &OutputPolicy::reading(&loaded.inputs()),
        )?),
        None => None,
    };
    let input_paths: Vec<PathBuf> = loaded.inputs().iter().map(|p| p.to_path_buf()).collect();
    let sc = loaded
        .scenario()
        .clone()
        .with_orbits(a.orbits)
        .map_err(|m| anyhow::anyhow!("--orbits {}: {m}", orbitlash::units::num(a.orbits)))?;
    let env = &sc.thermal.environment;
    let period = env.mean_period_s();
    let horizon = sc.run.duration_s;
    // every point of the orbit's table over the orbits shown, or the orbit's failure
    orbitlash::run::sim::check_orbit(env, horizon)
        .map_err(|e| anyhow::anyhow!("{}: {e}", loaded.file))?;
    let step = a.step_s.unwrap_or(period / 360.0);
    // the rows are only made for --csv and --plot
    if a.csv.is_some() || a.plot.is_some() {
        check_step(step, horizon, a.orbits)?;
    }
    // The faces (load name, geometry) and their nodes' names, in the scenario's order.
    let net = &sc.thermal.network;
    let faces: Vec<((String, Face), String)> = net
        .face_loads()
        .map(|(l, f)| ((l.name.clone(), *f), net.nodes[l.node].name.clone()))
        .collect();
    let utc = |t: f64| {
        env.utc_at(t)
            .map(|u| u.format("%Y-%m-%dT%H:%M:%S%.3fZ").to_string())
    };

    let mut o = String::new();
    outln!(
        o,
        "{}: {} ({}, {horizon:.1} s)",
        loaded.file,
        sc.name,
        orbitlash::units::orbits(a.orbits, 3)
    );
    for line in env.report() {
        outln!(o, "{line}");
    }
    let (b_lo, b_hi) = env.beta_range_rad(0.0, horizon);
    outln!(
        o,
        "  β over these orbits     {:.2}° … {:.2}°",
        b_lo.to_degrees(),
        b_hi.to_degrees()
    );

    let eclipses = eclipses(env, horizon);
    let dark = eclipses.iter().fold(0.0, |acc, (a, b)| acc + (b - a));
    outln!(
        o,
        "\neclipses: {} ({:.4} of the time in the umbra)",
        eclipses.len(),
        dark / horizon
    );
    if !eclipses.is_empty() {
        let head: Vec<&str> = if env.start_utc().is_some() {
            vec!["entry s", "exit s", "length s", "entry UTC"]
        } else {
            vec!["entry s", "exit s", "length s"]
        };
        let mut tb = table::new(
            &head,
            &[Align::Right, Align::Right, Align::Right, Align::Left],
        );
        for (e, x) in eclipses.iter().take(LISTED_ECLIPSES) {
            let mut row = vec![
                format!("{e:.3}"),
                format!("{x:.3}"),
                format!("{:.3}", x - e),
            ];
            if let Some(u) = utc(*e) {
                row.push(u);
            }
            tb.add_row(row);
        }
        o += &table::render(&tb, "  ");
        if eclipses.len() > LISTED_ECLIPSES {
            let lengths: Vec<f64> = eclipses.iter().map(|(a, b)| b - a).collect();
            let (lo, hi) = lengths
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| {
                    (l.min(*x), h.max(*x))
                });
            outln!(
                o,
                "  … and {} more; lengths {lo:.1} … {hi:.1} s",
                eclipses.len() - LISTED_ECLIPSES
            );
        }
    }

    if let (Some(file), Some(path)) = (csv.as_mut(), &a.csv) {
        let rows = (horizon / step).floor() as u64;
        let text = series(env, &faces, horizon, step, &utc);
        file.write_all(text.as_bytes())?;
        outln!(
            o,
            "\ncsv: {} ({} rows every {step:.3} s)",
            super::shown_path(path),
            rows + 1
        );
    }
    if let Some(f) = csv {
        f.commit()?;
    }
    if let Some(p) = &a.plot {
        let text = series(env, &faces, horizon, step, &|_| None);
        // a scenario with faces: each face's fluxes; without: β, flux and eclipses
        let fig = if faces.is_empty() {
            orbit_figure(
                &text,
                &eclipses,
                &format!("{}: the orbit's environment", sc.name),
            )?
        } else {
            face_figure(&text, &format!("{}: incident flux per face", sc.name))?
        };
        let inputs: Vec<&std::path::Path> = input_paths.iter().map(PathBuf::as_path).collect();
        super::plot::write_figure(&fig, p, &inputs)?;
        outln!(o, "plot: {}", super::shown_path(p));
    }
    print_out(&o)
}

/// The columns of the `--csv` series `text` (made without its utc cells; the header
/// still names the column): the header and the rows.
fn table_of(text: &str) -> (Vec<&str>, Vec<Vec<f64>>) {
    let mut lines = text.lines();
    let header: Vec<&str> = lines
        .next()
        .unwrap_or("")
        .split(',')
        .filter(|h| *h != "utc")
        .collect();
    let rows: Vec<Vec<f64>> = lines
        .map(|l| {
            l.split(',')
                .map(|c| c.parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    (header, rows)
}

/// The figure of a scenario without faces: β, the unshadowed solar flux and each
/// eclipse's length, from the `--csv` series `text` and the eclipses.
fn orbit_figure(
    text: &str,
    eclipses: &[(f64, f64)],
    title: &str,
) -> Result<orbitlash::plot::Figure> {
    use orbitlash::plot::orbit::{OrbitSeries, orbit_environment};
    let (header, rows) = table_of(text);
    let column = |name: &str| -> Result<Vec<f64>> {
        let i = header
            .iter()
            .position(|h| *h == name)
            .ok_or_else(|| anyhow::anyhow!("the environment series lacks {name}"))?;
        Ok(rows
            .iter()
            .map(|r| r.get(i).copied().unwrap_or(f64::NAN))
            .collect())
    };
    let (t, beta, flux) = (
        column("time_s")?,
        column("beta_deg")?,
        column("solar_flux_unshadowed_w_per_m2")?,
    );
    let s = OrbitSeries {
        time_s: &t,
        beta_deg: &beta,
        solar_flux_w_per_m2: &flux,
        eclipses_s: eclipses,
    };
    Ok(orbit_environment(title, &s)?)
}

/// The figure of the `--csv` series `text` (without its utc column).
fn face_figure(text: &str, title: &str) -> Result<orbitlash::plot::Figure> {
    use orbitlash::plot::faces::{FaceSeries, face_fluxes};
    let (header, rows) = table_of(text);
    let col = |name: &str| header.iter().position(|h| *h == name);
    let values = |i: usize| {
        rows.iter()
            .map(|r| r.get(i).copied().unwrap_or(f64::NAN))
            .collect::<Vec<f64>>()
    };
    let (Some(t), Some(lit)) = (col("time_s"), col("sun_fraction")) else {
        bail!("the environment series lacks time_s or sun_fraction");
    };
    let mut faces = Vec::new();
    for (i, h) in header.iter().enumerate() {
        if let Some(name) = h.strip_suffix(".solar_w_per_m2") {
            let (Some(a), Some(e)) = (
                col(&format!("{name}.albedo_w_per_m2")),
                col(&format!("{name}.earth_ir_w_per_m2")),
            ) else {
                continue;
            };
            faces.push(FaceSeries {
                name: name.to_string(),
                solar: values(i),
                albedo: values(a),
                earth_ir: values(e),
            });
        }
    }
    Ok(face_fluxes(title, &values(t), &values(lit), &faces)?)
}

/// Every eclipse (umbra entry, exit) from 0 to `horizon_s`, as the run would land on
/// them; one in progress at either end is cut there.
fn eclipses(env: &Environment, horizon: f64) -> Vec<(f64, f64)> {
    let mut eclipses: Vec<(f64, f64)> = Vec::new();
    let mut t = 0.0;
    let mut lit = env.sunlit(0.0);
    let mut entered = if lit { None } else { Some(0.0) };
    while let Some((tc, entering)) = env.next_shadow_crossing(t, horizon) {
        if entering {
            entered = Some(tc);
        } else if let Some(e) = entered.take() {
            eclipses.push((e, tc));
        }
        lit = !entering;
        t = tc;
    }
    if !lit && let Some(e) = entered {
        eclipses.push((e, horizon));
    }
    eclipses
}

/// The CSV text of `--csv`: a row every `step` s from 0 to `horizon` (see
/// `EnvironmentArgs::csv` for the columns).
fn series(
    env: &Environment,
    faces: &[((String, Face), String)],
    horizon: f64,
    step: f64,
    utc: &dyn Fn(f64) -> Option<String>,
) -> String {
    let start = env.start_utc();
    let mut header = vec!["time_s"];
    if start.is_some() {
        header.push("utc");
    }
    header.extend([
        "orbit_angle_deg",
        "sun_fraction",
        "beta_deg",
        "solar_flux_w_per_m2",
        "solar_flux_unshadowed_w_per_m2",
    ]);
    let mut header: Vec<String> = header.into_iter().map(String::from).collect();
    for ((face, _), node) in faces {
        for q in ["solar", "albedo", "earth_ir"] {
            header.push(format!("{node}.{face}.{q}_w_per_m2"));
        }
    }
    let mut text = header.join(",") + "\n";
    let rows = (horizon / step).floor() as u64;
    for k in 0..=rows {
        let t = (k as f64 * step).min(horizon);
        let s = env.state_with(t, true);
        let mut cells = vec![orbitlash::units::exact(t)];
        if let Some(u) = utc(t) {
            cells.push(u);
        }
        cells.push(format!("{:.6}", env.orbit_phase_deg(t)));
        cells.push(format!("{:.6}", env.sun_fraction(t)));
        cells.push(format!("{:.6}", s.beta_rad.to_degrees()));
        // the flux reaching the spacecraft, one definition with the log's
        // `/orbit/state` (dimmed in a penumbra, 0 in the umbra), and before any shadow
        let reaching = if env.sunlit(t) {
            s.solar_flux_w_per_m2
        } else {
            0.0
        };
        let unshadowed = env.state_with(t, false).solar_flux_w_per_m2;
        cells.push(format!("{reaching:.4}"));
        cells.push(format!("{unshadowed:.4}"));
        if !faces.is_empty() {
            let fe = env.face_environment(&env.state_with(t, env.sunlit(t)));
            for ((_, face), _) in faces {
                let i = incident(face, &fe);
                for v in [i.solar_w_per_m2, i.albedo_w_per_m2, i.earth_ir_w_per_m2] {
                    cells.push(format!("{v:.4}"));
                }
            }
        }
        text += &cells.join(",");
        text.push('\n');
    }
    text
}

/// A step for the series' rows that gives at least two over `horizon_s` (`orbits`): a
/// series, not a point; and at most [`MAX_ROWS`].
fn check_step(step: f64, horizon_s: f64, orbits: f64) -> Result<()> {
    if horizon_s / step > MAX_ROWS {
        bail!(
            "--step-s {step} over {horizon_s:.0} s gives {:.2e} rows; at most {MAX_ROWS:.0e}: use a longer step or fewer orbits",
            horizon_s / step
        );
    }
    if step > horizon_s / 2.0 {
        bail!(
            "--step-s {}: longer than half the {horizon_s:.1} s shown ({} orbit(s)), so the series would hold {} row(s); use at most {}",
            orbitlash::units::num(step),
            orbitlash::units::num(orbits),
            1 + (horizon_s / step).floor() as u64,
            orbitlash::units::num(horizon_s / 2.0)
        );
    }
    Ok(())
}
