//! Body-fixed faces and the attitude that orients them: the direct solar, Earth-albedo
//! and Earth-infrared flux each face receives.
//!
//! Frames. LVLH (local vertical, local horizontal): +x along the track (ram, in the
//! orbit plane, perpendicular to the radius), +y the negative orbit normal, +z nadir.
//! In it the Sun is `(−sin θ cos β, −sin β, −cos θ cos β)` for the orbit angle θ from
//! orbit noon and β, for circular and real orbits alike. The body frame follows the
//! attitude ([`Attitude`]); face normals are given in the body frame.
//!
//! Fluxes are incident, before absorptivity or emissivity:
//! - direct Sun: S cos⁺ of the Sun's angle on the face, S already dimmed in a penumbra
//!   and zero in the umbra;
//! - Earth infrared: q F, with F the view factor of a tilted plate to a sphere, closed
//!   form (Howell, *A Catalog of Radiation Heat Transfer Configuration Factors*, factor
//!   B-? "differential planar element to sphere, plane tilted"; the same in Gilmore,
//!   *Spacecraft Thermal Control Handbook*, vol. 1, ch. 2);
//! - Earth albedo: the sunlight the sunlit part of the Earth the face sees reflects, a
//!   Lambertian surface of uniform albedo a: E = ∫ (a S cos⁺ζ / π) cos⁺(n·u) dΩ over the
//!   Earth's disc as seen from the spacecraft, ζ the solar zenith angle where the
//!   direction u meets the ground; integrated numerically ([`ALBEDO_RINGS`] ×
//!   [`ALBEDO_SECTORS`] cells of the disc). Unlike the common shortcut a S F cos ζ at the
//!   sub-satellite point, this holds at high β and near the terminator.

use std::f64::consts::PI;

/// Rings (in the nadir angle) and sectors (in azimuth) of the albedo integral.
pub const ALBEDO_RINGS: usize = 24;
pub const ALBEDO_SECTORS: usize = 48;

/// How the spacecraft's body frame is oriented.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Attitude {
    /// Body axes on LVLH (+x ram, +y −orbit normal, +z nadir), turned by `yaw_rad`
    /// about +z (nadir).
    Nadir { yaw_rad: f64 },
    /// Body +z on the Sun, body +x as close to nadir as it can be (toward the ram when
    /// the Sun is at the zenith or nadir).
    Sun,
    /// Passively stabilised and tumbling: every face sees the average over all
    /// orientations (each orientation equally likely): S/4 of direct Sun, the Earth's
    /// solid angle over 4π of its infrared, a quarter of the albedo radiance
    /// integrated over the Earth's disc. Fits a slowly tumbling small satellite over an
    /// orbit, not its instants.
    Tumble,
    /// Inertially fixed: the unit quaternion `[w, x, y, z]` turning body axes into the
    /// inertial frame (TEME for a TLE orbit; for a circular orbit the orbit frame: +x
    /// toward orbit noon, +z the orbit normal).
    Inertial { quaternion: [f64; 4] },
    /// Spinning about the body axis `axis_body` (unit) at `rate_rad_per_s`, starting
    /// at t = 0 from the orientation of `quaternion` (as [`Attitude::Inertial`]): the
    /// spin axis stays fixed in the inertial frame. `averaged`: every face sees the
    /// mean over one turn ([`SPIN_PHASES`] phases) instead of the instant, for spins
    /// much faster than the nodes' time constants.
    Spin {
        quaternion: [f64; 4],
        axis_body: [f64; 3],
        rate_rad_per_s: f64,
        averaged: bool,
    },
}

/// Spin phases a spin-averaged face is evaluated at (the midpoints of equal arcs):
/// the mean of the direct Sun, max(cos, 0) over a turn, is then within 0.07 % of 1/π
/// whatever the phase (36 phases: 0.25 %).
pub const SPIN_PHASES: usize = 72;

/// A body-fixed flat face.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Face {
    /// Outward unit normal, body frame.
    pub normal_body: [f64; 3],
    pub area_m2: f64,
    /// Solar absorptivity α (direct Sun and albedo).
    pub absorptivity: f64,
    /// Infrared emissivity ε (Earth infrared absorbed; the face's own emission is a
    /// radiative coupling to space).
    pub emissivity: f64,
    pub attitude: Attitude,
}

/// What a face receives, W/m², before absorptivity.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Incident {
    pub solar_w_per_m2: f64,
    pub albedo_w_per_m2: f64,
    pub earth_ir_w_per_m2: f64,
}

/// The environment of the faces at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FaceEnvironment {
    /// Unit Sun direction in LVLH.
    pub sun_lvlh: [f64; 3],
    /// Direct solar flux at the spacecraft, W/m²: dimmed in a penumbra, 0 in the umbra.
    pub solar_w_per_m2: f64,
    /// Solar flux on the Earth, W/m² (no shadow).
    pub solar_on_earth_w_per_m2: f64,
    /// Orbit radius and Earth radius, m.
    pub radius_m: f64,
    pub earth_radius_m: f64,
    pub albedo: f64,
    pub earth_ir_w_per_m2: f64,
    /// The LVLH axes (x, y, z) in the inertial frame.
    pub lvlh_axes: [[f64; 3]; 3],
    /// Time since the run's t = 0, s (a spinning body's phase).
    pub t_s: f64,
}

/// The LVLH axes in the inertial frame of a spacecraft at `r` with orbit normal
/// `normal` (unit): z = −r̂, y = −normal, x = y × z.
pub fn lvlh_axes(r: [f64; 3], normal: [f64; 3]) -> [[f64; 3]; 3] {
    let z = unit([-r[0], -r[1], -r[2]]);
    let y = [-normal[0], -normal[1], -normal[2]];
    [cross(y, z), y, z]
}

/// The rotation matrix (columns: body axes in the inertial frame) of the unit
/// quaternion `[w, x, y, z]`.
pub fn quaternion_axes(q: [f64; 4]) -> [[f64; 3]; 3] {
    let [w, x, y, z] = q;
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y + w * z),
            2.0 * (x * z - w * y),
        ],
        [
            2.0 * (x * y - w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z + w * x),
        ],
        [
            2.0 * (x * z + w * y),
            2.0 * (y * z - w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

/// `v` turned by `angle_rad` about the unit axis `axis` (Rodrigues).
pub fn rotate_about(v: [f64; 3], axis: [f64; 3], angle_rad: f64) -> [f64; 3] {
    let (s, c) = angle_rad.sin_cos();
    let k = cross(axis, v);
    let d = dot(axis, v) * (1.0 - c);
    [
        v[0] * c + k[0] * s + axis[0] * d,
        v[1] * c + k[1] * s + axis[1] * d,
        v[2] * c + k[2] * s + axis[2] * d,
    ]
}

/// The Sun in LVLH for the orbit angle θ from orbit noon and β.
pub fn sun_lvlh(theta_rad: f64, beta_rad: f64) -> [f64; 3] {
    let (st, ct) = theta_rad.sin_cos();
    let (sb, cb) = beta_rad.sin_cos();
    [-st * cb, -sb, -ct * cb]
}

pub(crate) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub(crate) fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub(crate) fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

pub(crate) fn unit(a: [f64; 3]) -> [f64; 3] {
    let n = dot(a, a).sqrt();
    [a[0] / n, a[1] / n, a[2] / n]
}

/// The body axes (x, y, z) in LVLH under `attitude` with the Sun at `sun` and the
/// LVLH axes `lvlh` in the inertial frame.
/// `spin_rad` is the spin phase of a spinning body (ignored by the other modes).
pub fn body_axes(
    attitude: Attitude,
    sun: [f64; 3],
    lvlh: &[[f64; 3]; 3],
    spin_rad: f64,
) -> [[f64; 3]; 3] {
    let in_lvlh = |b: [[f64; 3]; 3]| {
        b.map(|axis| [dot(axis, lvlh[0]), dot(axis, lvlh[1]), dot(axis, lvlh[2])])
    };
    match attitude {
        Attitude::Inertial { quaternion } => in_lvlh(quaternion_axes(quaternion)),
        Attitude::Spin {
            quaternion,
            axis_body,
            ..
        } => {
            // body axis i, turned about the spin axis in the body frame, then carried
            // into the inertial frame by the starting orientation
            let b0 = quaternion_axes(quaternion);
            let turned = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
                .map(|e| rotate_about(e, axis_body, spin_rad));
            in_lvlh(
                turned.map(|v| {
                    [0, 1, 2].map(|j| v[0] * b0[0][j] + v[1] * b0[1][j] + v[2] * b0[2][j])
                }),
            )
        }
        Attitude::Nadir { yaw_rad } => {
            let (s, c) = yaw_rad.sin_cos();
            [[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]]
        }
        Attitude::Sun | Attitude::Tumble => {
            let z = sun;
            let nadir = [0.0, 0.0, 1.0];
            let along = |v: [f64; 3]| {
                let k = dot(v, z);
                [v[0] - k * z[0], v[1] - k * z[1], v[2] - k * z[2]]
            };
            let mut x = along(nadir);
            if dot(x, x) < 1e-12 {
                x = along([1.0, 0.0, 0.0]);
            }
            let x = unit(x);
            let y = cross(z, x);
            [x, y, z]
        }
    }
}

/// View factor from a plate whose normal makes angle ω with the direction to the
/// centre of a sphere seen at H = r/R radii (closed form, Howell's catalog).
pub fn plate_to_sphere_view_factor(cos_omega: f64, h: f64) -> f64 {
    let c = cos_omega.clamp(-1.0, 1.0);
    let omega = c.acos();
    let phi = (1.0 / h).asin();
    if omega <= PI / 2.0 - phi {
        return c / (h * h);
    }
    if omega >= PI / 2.0 + phi {
        return 0.0;
    }
    let x = (h * h - 1.0).sqrt();
    let s = omega.sin();
    let cot = c / s;
    let first = (x / (h * s)).clamp(-1.0, 1.0).asin();
    let second = (-x * cot).clamp(-1.0, 1.0).acos();
    let root = (1.0 - h * h * c * c).max(0.0).sqrt();
    (0.5 - first / PI + (c * second - x * root) / (PI * h * h)).max(0.0)
}

/// One ring of the Earth's disc seen from radius `r` (midpoint of its nadir angle η):
/// sin η, cos η, the distance along its directions to the ground, and the solid angle
/// of one of its [`ALBEDO_SECTORS`] cells.
struct Ring {
    se: f64,
    ce: f64,
    d: f64,
    cell: f64,
}

/// The [`ALBEDO_RINGS`] rings of the Earth's disc seen from radius `r`, outward.
fn rings(r: f64, earth_r: f64) -> impl Iterator<Item = Ring> {
    let eta_max = (earth_r / r).min(1.0).asin();
    let d_eta = eta_max / ALBEDO_RINGS as f64;
    let d_phi = 2.0 * PI / ALBEDO_SECTORS as f64;
    (0..ALBEDO_RINGS).map(move |i| {
        let eta = (i as f64 + 0.5) * d_eta;
        let (se, ce) = eta.sin_cos();
        Ring {
            se,
            ce,
            d: r * ce - (earth_r * earth_r - r * r * se * se).max(0.0).sqrt(),
            cell: se * d_eta * d_phi,
        }
    })
}

/// ∫ L(u) w(u) dΩ over the Earth's disc seen from radius `r` (LVLH: the Earth's centre
/// along +z), by the midpoint rule on [`ALBEDO_RINGS`] rings of nadir angle and
/// [`ALBEDO_SECTORS`] sectors: `radiance(point normal)` and `weight(direction)`.
pub fn over_earth_disc(
    r: f64,
    earth_r: f64,
    radiance: &dyn Fn([f64; 3]) -> f64,
    weight: &dyn Fn([f64; 3]) -> f64,
) -> f64 {
    let d_phi = 2.0 * PI / ALBEDO_SECTORS as f64;
    let mut sum = 0.0;
    for Ring { se, ce, d, cell } in rings(r, earth_r) {
        for j in 0..ALBEDO_SECTORS {
            let phi = (j as f64 + 0.5) * d_phi;
            let (sp, cp) = phi.sin_cos();
            let u = [se * cp, se * sp, ce];
            // ground point relative to the Earth's centre: spacecraft at −r ẑ
            let p = [
                d * u[0] / earth_r,
                d * u[1] / earth_r,
                (d * u[2] - r) / earth_r,
            ];
            let w = weight(u);
            if w > 0.0 {
                sum += radiance(p) * w * cell;
            }
        }
    }
    sum
}

/// The albedo radiance of every cell of the Earth's disc seen in environment `e`:
/// (direction from the spacecraft, radiance × the cell's solid angle), cells with no
/// sunlit ground left out. The faces of one instant share it: it is kept per thread
/// for the last environment asked for.
fn albedo_cells(e: &FaceEnvironment, out: &mut Vec<([f64; 3], f64)>) {
    out.clear();
    let (r, earth_r, sun) = (e.radius_m, e.earth_radius_m, e.sun_lvlh);
    let scale = e.albedo * e.solar_on_earth_w_per_m2 / PI;
    for Ring { se, ce, d, cell } in rings(r, earth_r) {
        for &(sp, cp) in sectors() {
            let u = [se * cp, se * sp, ce];
            let p = [
                d * u[0] / earth_r,
                d * u[1] / earth_r,
                (d * u[2] - r) / earth_r,
            ];
            let cos_zenith = dot(p, sun);
            if cos_zenith > 0.0 {
                out.push((u, scale * cos_zenith * cell));
            }
        }
    }
}

/// An environment and, for it, vectors each with a number: the albedo cells
/// (direction, radiance × solid angle), or the primed sums (normal, albedo).
type Cells = (Option<FaceEnvironment>, Vec<([f64; 3], f64)>);
thread_local! {
    /// The albedo cells of the last environment asked for on this thread.
    static CELLS: std::cell::RefCell<Cells> = const { std::cell::RefCell::new((None, Vec::new())) };
    /// The albedo seen along each normal of the last instant primed on this thread
    /// ([`prime_albedo`]).
    static PRIMED: std::cell::RefCell<Cells> = const { std::cell::RefCell::new((None, Vec::new())) };
}

/// `f` on the albedo cells of `e` (made when `e` is not the last asked for).
fn with_cells<R>(e: &FaceEnvironment, f: impl FnOnce(&[([f64; 3], f64)]) -> R) -> R {
    CELLS.with(|c| {
        let mut c = c.borrow_mut();
        if c.0.as_ref() != Some(e) {
            albedo_cells(e, &mut c.1);
            c.0 = Some(*e);
        }
        f(&c.1)
    })
}

/// Σ over the albedo cells of `e` of radiance × cell × weight(direction).
fn albedo_sum(e: &FaceEnvironment, weight: &dyn Fn([f64; 3]) -> f64) -> f64 {
    with_cells(e, |cells| {
        // a fold from +0: an empty sum is 0, not the −0 of `Iterator::sum`
        cells.iter().fold(0.0, |acc, (u, l)| {
            let w = weight(*u);
            if w > 0.0 { acc + l * w } else { acc }
        })
    })
}

/// The albedo a face of normal `n` (LVLH) sees in `e`: `albedo_sum` with weight
/// n · u, taken from the sums [`prime_albedo`] made for this instant when `n` is
/// among them.
fn albedo_along(e: &FaceEnvironment, n: [f64; 3]) -> f64 {
    let primed = PRIMED.with(|p| {
        let p = p.borrow();
        if p.0.as_ref() == Some(e) {
            p.1.iter().find(|(m, _)| *m == n).map(|&(_, v)| v)
        } else {
            None
        }
    });
    primed.unwrap_or_else(|| albedo_sum(e, &|u| dot(n, u)))
}

/// Sums the albedo of every face of `faces` that sees one orientation at this instant
/// (not tumbling, not spin-averaged) in one pass over the cells of `e`, one
/// accumulator per face, each in the order of [`albedo_sum`]: the same numbers, but
/// the faces' chains of additions overlap in the processor instead of running one
/// after the other. [`incident`] then takes them from there.
pub fn prime_albedo<'f>(e: &FaceEnvironment, faces: impl Iterator<Item = &'f Face>) {
    if !(e.albedo > 0.0 && e.solar_on_earth_w_per_m2 > 0.0) {
        return;
    }
    let normals: Vec<[f64; 3]> = faces
        .filter_map(|f| one_phase(f, e).map(|phase| lvlh_normal(f, e, phase)))
        .collect();
    if normals.len() < 2 {
        return;
    }
    let sums = with_cells(e, |cells| {
        let mut acc = vec![0.0; normals.len()];
        for (u, l) in cells {
            for (a, n) in acc.iter_mut().zip(&normals) {
                let w = dot(*n, *u);
                if w > 0.0 {
                    *a += l * w;
                }
            }
        }
        acc
    });
    PRIMED.with(|p| {
        let mut p = p.borrow_mut();
        p.0 = Some(*e);
        p.1.clear();
        p.1.extend(normals.into_iter().zip(sums));
    });
}

/// The spin phase at which `face` is seen at this instant, when it is seen at one
/// (None: tumbling, or averaged over its spin).
fn one_phase(face: &Face, e: &FaceEnvironment) -> Option<f64> {
    match face.attitude {
        Attitude::Tumble => None,
        Attitude::Spin {
            rate_rad_per_s,
            averaged,
            ..
        } => (!averaged).then_some(rate_rad_per_s * e.t_s),
        _ => Some(0.0),
    }
}

/// Σ over the albedo cells of `e` of radiance × cell: [`albedo_sum`] with weight 1,
/// the same cells and the same sum to rounding, without keeping the cells; kept per
/// thread for the last environment asked for, which every tumbling face of one instant
/// shares. A cell's cos ζ is A_ring · c_sector + B_ring (c_sector = the sector's
/// direction · the Sun's horizontal part, computed once per instant), so a cell costs
/// two flops: this sum was two thirds of a tumbling model's run.
fn albedo_total(e: &FaceEnvironment) -> f64 {
    use std::cell::Cell;
    thread_local! {
        static TOTAL: Cell<Option<(FaceEnvironment, f64)>> = const { Cell::new(None) };
    }
    if let Some((last, total)) = TOTAL.get()
        && last == *e
    {
        return total;
    }
    let (r, earth_r, sun) = (e.radius_m, e.earth_radius_m, e.sun_lvlh);
    let scale = e.albedo * e.solar_on_earth_w_per_m2 / PI;
    let mut horizontal = [0.0; ALBEDO_SECTORS];
    for (h, &(sp, cp)) in horizontal.iter_mut().zip(sectors()) {
        *h = cp * sun[0] + sp * sun[1];
    }
    let mut all = [(0.0, 0.0, 0.0); ALBEDO_RINGS];
    for (slot, Ring { se, ce, d, cell }) in all.iter_mut().zip(rings(r, earth_r)) {
        // the ground point d·u − r ẑ over the Earth's radius, against the Sun
        *slot = (d * se / earth_r, (d * ce - r) / earth_r * sun[2], cell);
    }
    // Each ring's sum over its sectors is a chain of dependent additions; four rings
    // are summed side by side, each in its own order (the same numbers as one ring at
    // a time, from −0 as `Iterator::sum`), so that the processor overlaps the chains.
    let mut total = 0.0;
    for group in all.chunks_exact(RINGS_TOGETHER) {
        let mut lit = [-0.0f64; RINGS_TOGETHER];
        for h in &horizontal {
            for (l, &(a, b, _)) in lit.iter_mut().zip(group) {
                *l += (a * h + b).max(0.0);
            }
        }
        for (l, &(_, _, cell)) in lit.iter().zip(group) {
            total += scale * l * cell;
        }
    }
    TOTAL.set(Some((*e, total)));
    total
}

/// Rings of [`albedo_total`] summed side by side.
const RINGS_TOGETHER: usize = 4;
const _: () = assert!(ALBEDO_RINGS.is_multiple_of(RINGS_TOGETHER));

/// (sin, cos) of the middle of each of the [`ALBEDO_SECTORS`] sectors.
fn sectors() -> &'static [(f64, f64)] {
    use std::sync::OnceLock;
    static SECTORS: OnceLock<Vec<(f64, f64)>> = OnceLock::new();
    SECTORS.get_or_init(|| {
        let d_phi = 2.0 * PI / ALBEDO_SECTORS as f64;
        (0..ALBEDO_SECTORS)
            .map(|j| ((j as f64 + 0.5) * d_phi).sin_cos())
            .collect()
    })
}

/// What `face` receives in environment `e`.
pub fn incident(face: &Face, e: &FaceEnvironment) -> Incident {
    let h = e.radius_m / e.earth_radius_m;
    let lit_earth = e.albedo > 0.0 && e.solar_on_earth_w_per_m2 > 0.0;
    if let Attitude::Tumble = face.attitude {
        let cap = 1.0 - (1.0 - 1.0 / (h * h)).max(0.0).sqrt();
        let albedo_all = if lit_earth { albedo_total(e) } else { 0.0 };
        return Incident {
            solar_w_per_m2: e.solar_w_per_m2 / 4.0,
            albedo_w_per_m2: albedo_all / 4.0,
            earth_ir_w_per_m2: e.earth_ir_w_per_m2 * cap / 2.0,
        };
    }
    if let Attitude::Spin {
        rate_rad_per_s,
        averaged,
        ..
    } = face.attitude
    {
        let phase = rate_rad_per_s * e.t_s;
        if !averaged {
            return oriented(face, e, phase);
        }
        let mut sum = Incident::default();
        for k in 0..SPIN_PHASES {
            let i = oriented(
                face,
                e,
                phase + (k as f64 + 0.5) * 2.0 * PI / SPIN_PHASES as f64,
            );
            sum.solar_w_per_m2 += i.solar_w_per_m2;
            sum.albedo_w_per_m2 += i.albedo_w_per_m2;
            sum.earth_ir_w_per_m2 += i.earth_ir_w_per_m2;
        }
        let n = SPIN_PHASES as f64;
        return Incident {
            solar_w_per_m2: sum.solar_w_per_m2 / n,
            albedo_w_per_m2: sum.albedo_w_per_m2 / n,
            earth_ir_w_per_m2: sum.earth_ir_w_per_m2 / n,
        };
    }
    oriented(face, e, 0.0)
}

/// `face`'s outward normal in LVLH in environment `e`, its body at spin phase
/// `spin_rad`.
fn lvlh_normal(face: &Face, e: &FaceEnvironment, spin_rad: f64) -> [f64; 3] {
    let axes = body_axes(face.attitude, e.sun_lvlh, &e.lvlh_axes, spin_rad);
    let nb = face.normal_body;
    [
        nb[0] * axes[0][0] + nb[1] * axes[1][0] + nb[2] * axes[2][0],
        nb[0] * axes[0][1] + nb[1] * axes[1][1] + nb[2] * axes[2][1],
        nb[0] * axes[0][2] + nb[1] * axes[1][2] + nb[2] * axes[2][2],
    ]
}

/// What `face` receives in environment `e` with its body at spin phase `spin_rad`.
fn oriented(face: &Face, e: &FaceEnvironment, spin_rad: f64) -> Incident {
    let h = e.radius_m / e.earth_radius_m;
    let sun = e.sun_lvlh;
    let lit_earth = e.albedo > 0.0 && e.solar_on_earth_w_per_m2 > 0.0;
    let n = lvlh_normal(face, e, spin_rad);
    let albedo = if lit_earth { albedo_along(e, n) } else { 0.0 };
    Incident {
        solar_w_per_m2: e.solar_w_per_m2 * dot(n, sun).max(0.0),
        albedo_w_per_m2: albedo,
        earth_ir_w_per_m2: e.earth_ir_w_per_m2 * plate_to_sphere_view_factor(n[2], h),
    }
}

/// The power `face` absorbs, W.
pub fn absorbed_w(face: &Face, e: &FaceEnvironment) -> f64 {
    let i = incident(face, e);
    face.area_m2
        * (face.absorptivity * (i.solar_w_per_m2 + i.albedo_w_per_m2)
            + face.emissivity * i.earth_ir_w_per_m2)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The numerical disc integral of a uniform radiance against the closed-form view
    /// factor: two methods for F, every orientation from nadir to zenith.
    #[test]
    fn view_factor_closed_form_agrees_with_the_disc_integral() {
        for h in [1.05, 1.1, 1.3, 2.0] {
            for k in 0..=36 {
                let omega = (k as f64 * 5.0).to_radians();
                let n = [omega.sin(), 0.0, omega.cos()];
                let numeric = over_earth_disc(h, 1.0, &|_| 1.0 / PI, &|u| dot(n, u)).max(0.0);
                let closed = plate_to_sphere_view_factor(omega.cos(), h);
                assert!(
                    (numeric - closed).abs() < 2e-3 * (1.0 / (h * h)),
                    "H {h}, ω {}°: {numeric} vs {closed}",
                    k * 5
                );
            }
        }
    }

    /// The albedo of a model's faces summed in one pass ([`prime_albedo`]) is each
    /// face's own sum, bit for bit, for faces all round and Suns all round.
    #[test]
    fn core_primed_albedo_is_each_face_s_own_sum_bit_for_bit() {
        let cube: Vec<Face> = [
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
            [0.6, 0.0, 0.8],
        ]
        .into_iter()
        .map(|normal_body| Face {
            normal_body,
            area_m2: 0.01,
            absorptivity: 0.7,
            emissivity: 0.8,
            attitude: Attitude::Nadir { yaw_rad: 0.3 },
        })
        .collect();
        let mut lit = 0;
        for j in 0..12 {
            let (th, ph) = (j as f64 * 0.29 + 0.1, j as f64 * 0.83);
            let e = FaceEnvironment {
                sun_lvlh: [th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()],
                solar_w_per_m2: 1361.0,
                solar_on_earth_w_per_m2: 1361.0,
                radius_m: 6_878e3,
                earth_radius_m: 6_378e3,
                albedo: 0.3,
                earth_ir_w_per_m2: 237.0,
                lvlh_axes: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
                t_s: 100.0 + j as f64,
            };
            // each face alone, before any priming of this instant
            let alone: Vec<f64> = cube
                .iter()
                .map(|f| {
                    let n = lvlh_normal(f, &e, 0.0);
                    albedo_sum(&e, &|u| dot(n, u))
                })
                .collect();
            prime_albedo(&e, cube.iter());
            let primed = PRIMED.with(|p| p.borrow().1.len());
            assert_eq!(primed, cube.len());
            for (f, a) in cube.iter().zip(&alone) {
                let got = incident(f, &e).albedo_w_per_m2;
                assert_eq!(
                    got.to_bits(),
                    a.to_bits(),
                    "{:?}: {got} vs {a}",
                    f.normal_body
                );
            }
            lit += alone.iter().filter(|&&a| a > 0.0).count();
        }
        // the day side seen too, not only zeros compared
        assert!(lit > 20, "{lit}");
    }

    /// The tumbling total (two flops a cell) against the cell-by-cell sum it replaces,
    /// for Suns all round the sky, above and below the horizon, at three heights.
    #[test]
    fn core_albedo_total_is_the_cell_sum() {
        for (radius, k) in [(6_778e3, 0), (7_178e3, 1), (12_000e3, 2)] {
            for j in 0..40 {
                let (th, ph) = (j as f64 * 0.157 + 0.05 * k as f64, j as f64 * 0.61);
                let sun = [th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()];
                let e = FaceEnvironment {
                    sun_lvlh: sun,
                    solar_w_per_m2: 1361.0,
                    solar_on_earth_w_per_m2: 1361.0,
                    radius_m: radius,
                    earth_radius_m: 6_378e3,
                    albedo: 0.3,
                    earth_ir_w_per_m2: 237.0,
                    lvlh_axes: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
                    t_s: j as f64,
                };
                let fast = albedo_total(&e);
                let cells = albedo_sum(&e, &|_| 1.0);
                assert!(
                    (fast - cells).abs() <= 1e-12 * cells.abs().max(1.0),
                    "r {radius}, Sun {sun:?}: {fast} vs {cells}"
                );
            }
        }
    }
}
