//! The figure of `environment --plot`: each face's incident flux over the orbit,
//! direct Sun, Earth albedo and Earth infrared in three panels, one line per face,
//! eclipses shaded, the legend beside the panels.

use plotters::prelude::*;

use super::labels::Placer;
use super::{
    ECLIPSE, FAMILY, Figure, Label, PlotError, Swatch, decimals, draw_err, nice_range, nice_step,
    palette, time_unit,
};

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
    const W: u32 = 1100;
    const H: u32 = 820;
    const LEGEND_X: i32 = 880;
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
        root.draw(&Text::new(
            title.to_string(),
            (20, 12),
            (FAMILY, 19).into_font().color(&BLACK),
        ))
        .map_err(draw_err)?;
        let r = Placer::text_box(title, 19.0, 20.0, 12.0);
        placer.avoid(r);
        labels.push(Label {
            text: title.to_string(),
            rect: r,
        });
        let kinds: [(&str, Flux); 3] = [
            ("direct Sun (W/m²)", |f| &f.solar),
            ("Earth albedo (W/m²)", |f| &f.albedo),
            ("Earth infrared (W/m²)", |f| &f.earth_ir),
        ];
        let panel_h = 250;
        for (k, (desc, get)) in kinds.iter().enumerate() {
            let y_top = 46 + k as i32 * panel_h;
            let last = k + 1 == kinds.len();
            let area = root
                .clone()
                .shrink((0, y_top), (LEGEND_X as u32, panel_h as u32 - 6));
            let (lo, hi) = faces
                .iter()
                .flat_map(|f| get(f).iter())
                .filter(|v| v.is_finite())
                .fold((0.0f64, f64::NEG_INFINITY), |(a, b), v| {
                    (a.min(*v), b.max(*v))
                });
            let (ylo, yhi) = nice_range(lo, hi.max(lo + 1.0));
            let mut chart = ChartBuilder::on(&area)
                .margin_left(10)
                .margin_right(10)
                .x_label_area_size(if last { 50 } else { 26 })
                .y_label_area_size(70)
                .build_cartesian_2d(x0..x1, ylo..yhi)
                .map_err(draw_err)?;
            let ystep = nice_step(yhi - ylo, 5.0);
            let xstep = nice_step(x1 - x0, 10.0);
            let xdec = decimals(xstep);
            let yfmt = |v: &f64| format!("{v:.0}");
            let xfmt = move |v: &f64| format!("{v:.xdec$}");
            let mut mesh = chart.configure_mesh();
            mesh.y_desc(*desc)
                .y_labels(((yhi - ylo) / ystep).round() as usize + 1)
                .x_labels(((x1 - x0) / xstep).round() as usize + 1)
                .y_label_formatter(&yfmt)
                .x_label_formatter(&xfmt)
                .light_line_style(TRANSPARENT)
                .bold_line_style(RGBColor(230, 230, 230))
                .label_style((FAMILY, 13))
                .axis_desc_style((FAMILY, 14));
            if last {
                mesh.x_desc(format!("time ({unit})"));
            }
            mesh.draw().map_err(draw_err)?;
            chart
                .draw_series(
                    eclipses.iter().map(|&(a, b)| {
                        Rectangle::new([(tx(a), ylo), (tx(b), yhi)], ECLIPSE.filled())
                    }),
                )
                .map_err(draw_err)?;
            for (i, (j, _)) in groups.iter().enumerate() {
                let f = &faces[*j];
                chart
                    .draw_series(LineSeries::new(
                        time_s
                            .iter()
                            .zip(get(f).iter())
                            .filter(|(_, v)| v.is_finite())
                            .map(|(t, v)| (tx(*t), *v)),
                        palette(i).stroke_width(2),
                    ))
                    .map_err(draw_err)?;
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
    Ok(Figure {
        svg,
        width: W,
        height: H,
        labels,
    })
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
