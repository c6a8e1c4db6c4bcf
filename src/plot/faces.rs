//! The figure of `environment --plot`: each face's incident flux over the orbit,
//! direct Sun, Earth albedo and Earth infrared in three panels, one line per face,
//! eclipses shaded, the legend beside the panels.

use plotters::prelude::*;

use super::labels::Placer;
use super::panels::{self, H, LEGEND_X, W};
use super::{ECLIPSE, Figure, PlotError, Swatch, draw_err, nice_range, palette, time_unit};

/// One face's fluxes, W/m² (incident, before absorptivity), at the figure's times.
#[derive(Debug, Clone)]
pub struct FaceSeries {
    pub name: String,
    pub solar: Vec<f64>,
    pub albedo: Vec<f64>,
    pub earth_ir: Vec<f64>,
}

/// Which of a face's fluxes a panel draws.
type Flux = fn(&FaceSeries) -> &Vec<f64>;

/// `time_s` ascending; `sunlit` 0 … 1 (penumbra between).
pub fn face_fluxes(
    title: &str,
    time_s: &[f64],
    sunlit: &[f64],
    faces: &[FaceSeries],
) -> Result<Figure, PlotError> {
    if time_s.len() < 2 {
        return Err(PlotError::Data("fewer than two times to plot".into()));
    }
    let span = (time_s[time_s.len() - 1] - time_s[0]).max(1.0);
    let (unit_s, unit) = time_unit(span);
    let tx = |t: f64| t / unit_s;
    let (x0, x1) = (tx(time_s[0]), tx(time_s[time_s.len() - 1]));
    // eclipse spans: sunlit below a half
    let mut eclipses = Vec::new();
    let mut open: Option<f64> = None;
    for (i, &l) in sunlit.iter().enumerate() {
        match (open, l < 0.5) {
            (None, true) => open = Some(time_s[i]),
            (Some(a), false) => {
                eclipses.push((a, time_s[i]));
                open = None;
            }
            _ => {}
        }
    }
    if let Some(a) = open {
        eclipses.push((a, time_s[time_s.len() - 1]));
    }
    let groups = same_flux_groups(faces);
    let mut svg = String::new();
    let mut labels = Vec::new();
    let mut placer = Placer::new();
    {
        let root = SVGBackend::with_string(&mut svg, (W, H)).into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        panels::title(&root, title, &mut placer, &mut labels)?;
        let kinds: [(&str, Flux); 3] = [
            ("direct Sun (W/m²)", |f| &f.solar),
            ("Earth albedo (W/m²)", |f| &f.albedo),
            ("Earth infrared (W/m²)", |f| &f.earth_ir),
        ];
        let shade: Vec<(f64, f64)> = eclipses.iter().map(|&(a, b)| (tx(a), tx(b))).collect();
        for (k, (desc, get)) in kinds.iter().enumerate() {
            let last = k + 1 == kinds.len();
            let area = panels::area(&root, k);
            let (lo, hi) = faces
                .iter()
                .flat_map(|f| get(f).iter())
                .filter(|v| v.is_finite())
                .fold((0.0f64, f64::NEG_INFINITY), |(a, b), v| {
                    (a.min(*v), b.max(*v))
                });
            let axes = panels::Axes {
                x: (x0, x1),
                y: nice_range(lo, hi.max(lo + 1.0)),
                desc,
                y_decimals: Some(0),
                time_desc: last.then(|| format!("time ({unit})")),
            };
            let chart = panels::chart(&area, &axes, &shade)?;
            for (i, (j, _)) in groups.iter().enumerate() {
                let f = &faces[*j];
                super::fine::line(
                    &chart,
                    time_s
                        .iter()
                        .zip(get(f).iter())
                        .filter(|(_, v)| v.is_finite())
                        .map(|(t, v)| (tx(*t), *v)),
                    palette(i),
                    2.0,
                )?;
            }
            if k == 0 {
                let (_, yr) = chart.plotting_area().get_pixel_range();
                let mut entries = legend_entries(&groups);
                if !eclipses.is_empty() {
                    entries.push(("eclipse".into(), Swatch::Patch(ECLIPSE)));
                }
                super::legend(
                    &root,
                    &mut placer,
                    &mut labels,
                    LEGEND_X,
                    yr.start as f64,
                    &entries,
                )?;
            }
        }
        root.present().map_err(draw_err)?;
    }
    Ok(Figure::new(svg, W, H, labels))
}

/// The faces grouped by equal fluxes (a tumble-averaged attitude gives every face the
/// orientation average): per group its first face's index and every face's name. One
/// line per group is drawn: drawn apart, the last would hide the others.
fn same_flux_groups(faces: &[FaceSeries]) -> Vec<(usize, Vec<&str>)> {
    let mut groups: Vec<(usize, Vec<&str>)> = Vec::new();
    for (i, f) in faces.iter().enumerate() {
        let same =
            |g: &FaceSeries| g.solar == f.solar && g.albedo == f.albedo && g.earth_ir == f.earth_ir;
        match groups.iter_mut().find(|(j, _)| same(&faces[*j])) {
            Some((_, names)) => names.push(&f.name),
            None => groups.push((i, vec![&f.name])),
        }
    }
    groups
}

/// The legend's entries: per group its first face beside the line's colour, the
/// others under it (`= name`) and a note that they share the line.
fn legend_entries(groups: &[(usize, Vec<&str>)]) -> Vec<(String, Swatch)> {
    let mut entries = Vec::new();
    for (i, (_, names)) in groups.iter().enumerate() {
        entries.push((names[0].to_string(), Swatch::Line(palette(i), 3)));
        for n in &names[1..] {
            entries.push((format!("= {n}"), Swatch::None));
        }
        if names.len() > 1 {
            entries.push(("(the same fluxes: one line)".into(), Swatch::None));
        }
    }
    entries
}
