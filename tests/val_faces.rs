//! Faces against closed forms and a second method: a nadir face sees Earth infrared
//! q (R/r)² and a zenith face none; a Sun-pointing face sees S; the direct Sun summed
//! over a cube's six faces is S times the cube's projected area (A (|sx| + |sy| + |sz|));
//! the tumble-averaged fluxes equal the average of oriented faces over uniformly
//! random orientations; albedo vanishes when the visible Earth is dark and peaks on a
//! nadir face under the Sun.

use orbitlash::orbit::faces::{
    Attitude, Face, FaceEnvironment, incident, lvlh_axes, plate_to_sphere_view_factor, sun_lvlh,
};

const R: f64 = 6_378_137.0;

fn env(theta_deg: f64, beta_deg: f64, h_m: f64) -> FaceEnvironment {
    FaceEnvironment {
        sun_lvlh: sun_lvlh(theta_deg.to_radians(), beta_deg.to_radians()),
        solar_w_per_m2: 1361.0,
        solar_on_earth_w_per_m2: 1361.0,
        radius_m: R + h_m,
        earth_radius_m: R,
        albedo: 0.3,
        earth_ir_w_per_m2: 237.0,
        // the orbit frame of a circular orbit: x toward orbit noon, z the normal
        lvlh_axes: lvlh_axes(
            [
                theta_deg.to_radians().cos(),
                theta_deg.to_radians().sin(),
                0.0,
            ],
            [0.0, 0.0, 1.0],
        ),
        t_s: 0.0,
    }
}

fn face(normal: [f64; 3], attitude: Attitude) -> Face {
    Face {
        normal_body: normal,
        area_m2: 1.0,
        absorptivity: 1.0,
        emissivity: 1.0,
        attitude,
    }
}

const NADIR: Attitude = Attitude::Nadir { yaw_rad: 0.0 };

#[test]
fn val_closed_form_nadir_and_zenith_earth_ir() {
    for h in [300e3, 600e3, 1000e3] {
        let e = env(30.0, 20.0, h);
        let nadir = incident(&face([0.0, 0.0, 1.0], NADIR), &e);
        let zenith = incident(&face([0.0, 0.0, -1.0], NADIR), &e);
        let want = 237.0 * (R / (R + h)).powi(2);
        assert!((nadir.earth_ir_w_per_m2 - want).abs() < 1e-9 * want);
        assert_eq!(zenith.earth_ir_w_per_m2, 0.0);
        assert_eq!(zenith.albedo_w_per_m2, 0.0);
        // a face tangent to the Earth (normal along the track) sees part of it
        let side = plate_to_sphere_view_factor(0.0, (R + h) / R);
        assert!(side > 0.0 && side < (R / (R + h)).powi(2));
    }
}

#[test]
fn val_closed_form_sun_pointing_face_and_cube_projected_area() {
    for (theta, beta) in [(0.0, 0.0), (37.0, 20.0), (120.0, 60.0), (250.0, -45.0)] {
        let e = env(theta, beta, 600e3);
        let sun_face = incident(&face([0.0, 0.0, 1.0], Attitude::Sun), &e);
        assert!((sun_face.solar_w_per_m2 - 1361.0).abs() < 1e-9);
        let s = e.sun_lvlh;
        for attitude in [NADIR, Attitude::Nadir { yaw_rad: 0.7 }, Attitude::Sun] {
            let mut total = 0.0;
            for n in [
                [1.0, 0.0, 0.0],
                [-1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, -1.0, 0.0],
                [0.0, 0.0, 1.0],
                [0.0, 0.0, -1.0],
            ] {
                total += incident(&face(n, attitude), &e).solar_w_per_m2;
            }
            // the cube's projected area is frame-independent only through the sum of
            // |components| in the body frame; for a yaw or Sun attitude compare with
            // the body-frame Sun, for nadir with LVLH directly
            let projected = match attitude {
                Attitude::Sun => 1.0,
                Attitude::Nadir { yaw_rad } => {
                    let (sy, cy) = yaw_rad.sin_cos();
                    let bx = cy * s[0] + sy * s[1];
                    let by = -sy * s[0] + cy * s[1];
                    bx.abs() + by.abs() + s[2].abs()
                }
                Attitude::Tumble | Attitude::Inertial { .. } | Attitude::Spin { .. } => {
                    unreachable!()
                }
            };
            assert!(
                (total - 1361.0 * projected).abs() < 1e-9 * 1361.0,
                "θ {theta}, β {beta}: {total} vs {}",
                1361.0 * projected
            );
        }
    }
}

/// Uniformly random unit vectors from a fixed-seed generator (xorshift).
fn random_normals(n: usize) -> Vec<[f64; 3]> {
    let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut next = || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| {
            let z = 2.0 * next() - 1.0;
            let phi = 2.0 * std::f64::consts::PI * next();
            let r = (1.0 - z * z).sqrt();
            [r * phi.cos(), r * phi.sin(), z]
        })
        .collect()
}

#[test]
fn val_second_method_tumble_average_of_random_orientations() {
    let normals = random_normals(4000);
    for (theta, beta, h) in [(0.0, 0.0, 500e3), (60.0, 40.0, 800e3), (150.0, 10.0, 400e3)] {
        let e = env(theta, beta, h);
        let tumble = incident(&face([1.0, 0.0, 0.0], Attitude::Tumble), &e);
        let (mut sol, mut alb, mut ir) = (0.0, 0.0, 0.0);
        for n in &normals {
            let i = incident(&face(*n, NADIR), &e);
            sol += i.solar_w_per_m2;
            alb += i.albedo_w_per_m2;
            ir += i.earth_ir_w_per_m2;
        }
        let k = normals.len() as f64;
        // Monte Carlo over 4000 orientations: about 1.5 % of the mean
        for (name, mc, avg) in [
            ("solar", sol / k, tumble.solar_w_per_m2),
            ("albedo", alb / k, tumble.albedo_w_per_m2),
            ("earth_ir", ir / k, tumble.earth_ir_w_per_m2),
        ] {
            assert!(
                (mc - avg).abs() <= 0.04 * avg + 1e-9,
                "θ {theta}: {name} random average {mc} vs tumble {avg}"
            );
        }
    }
}

#[test]
fn val_albedo_dark_earth_and_subsolar_peak() {
    // orbit midnight at β = 0: the visible Earth is in darkness
    let night = incident(&face([0.0, 0.0, 1.0], NADIR), &env(180.0, 0.0, 600e3));
    assert_eq!(night.albedo_w_per_m2, 0.0);
    // orbit noon at β = 0: below the Sun, a nadir face sees a S F cos ζ with ζ small
    // over the cap; bounded by the uniform-radiance value a S (R/r)² and above 80 % of it
    let e = env(0.0, 0.0, 600e3);
    let noon = incident(&face([0.0, 0.0, 1.0], NADIR), &e);
    let bound = 0.3 * 1361.0 * (R / (R + 600e3)).powi(2);
    assert!(noon.albedo_w_per_m2 < bound && noon.albedo_w_per_m2 > 0.8 * bound);
    // and falls as the spacecraft goes round toward the terminator
    let later = incident(&face([0.0, 0.0, 1.0], NADIR), &env(60.0, 0.0, 600e3));
    assert!(later.albedo_w_per_m2 < noon.albedo_w_per_m2);
}

/// An inertially fixed face pointed at the Sun (in the orbit frame the Sun is
/// (cos β, 0, sin β)) sees S all round the orbit; one along the orbit normal sees
/// S sin β, as the nadir-pointing body's −Y face does; a quaternion of 90° about z
/// turns body +x onto inertial +y.
#[test]
fn val_closed_form_inertial_attitude() {
    let identity = Attitude::Inertial {
        quaternion: [1.0, 0.0, 0.0, 0.0],
    };
    let quarter = Attitude::Inertial {
        quaternion: [
            std::f64::consts::FRAC_1_SQRT_2,
            0.0,
            0.0,
            std::f64::consts::FRAC_1_SQRT_2,
        ],
    };
    for beta in [0.0f64, 25.0, 60.0] {
        let b = beta.to_radians();
        for theta in [0.0, 45.0, 100.0, 200.0, 300.0] {
            let e = env(theta, beta, 600e3);
            let at_sun = incident(&face([b.cos(), 0.0, b.sin()], identity), &e);
            assert!(
                (at_sun.solar_w_per_m2 - 1361.0).abs() < 1e-9,
                "θ {theta}, β {beta}"
            );
            let normal = incident(&face([0.0, 0.0, 1.0], identity), &e);
            let minus_y = incident(&face([0.0, -1.0, 0.0], NADIR), &e);
            assert!((normal.solar_w_per_m2 - minus_y.solar_w_per_m2).abs() < 1e-9);
            assert!((normal.earth_ir_w_per_m2 - minus_y.earth_ir_w_per_m2).abs() < 1e-9);
            // body +x turned onto inertial +y, which is the Sun-less in-plane axis
            let turned = incident(&face([1.0, 0.0, 0.0], quarter), &e);
            let plain = incident(&face([0.0, 1.0, 0.0], identity), &e);
            assert!((turned.solar_w_per_m2 - plain.solar_w_per_m2).abs() < 1e-9);
            assert!((turned.albedo_w_per_m2 - plain.albedo_w_per_m2).abs() < 1e-9);
        }
    }
}

/// A body spinning about the orbit normal (the inertial z of a circular orbit): at
/// each instant its faces see what the inertially fixed body turned by the spin angle
/// sees (Rodrigues against the quaternion of that turn); a face along the spin axis
/// sees what it sees without the spin; spin-averaged, a face on the equator of the
/// spin sees the direct Sun S/π with the Sun in the spin plane (β = 0) — the mean of
/// max(cos, 0) over a turn.
#[test]
fn val_closed_form_spin_attitude() {
    let rate = 7f64.to_radians();
    let spin = |averaged| Attitude::Spin {
        quaternion: [1.0, 0.0, 0.0, 0.0],
        axis_body: [0.0, 0.0, 1.0],
        rate_rad_per_s: rate,
        averaged,
    };
    let fixed = Attitude::Inertial {
        quaternion: [1.0, 0.0, 0.0, 0.0],
    };
    for t in [0.0, 3.0, 11.5, 40.0] {
        let phi: f64 = rate * t;
        let turned = Attitude::Inertial {
            quaternion: [(phi / 2.0).cos(), 0.0, 0.0, (phi / 2.0).sin()],
        };
        for theta in [0.0, 70.0, 150.0] {
            let mut e = env(theta, 30.0, 600e3);
            e.t_s = t;
            for n in [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.6, 0.0, 0.8]] {
                let a = incident(&face(n, spin(false)), &e);
                let b = incident(&face(n, turned), &e);
                for (x, y) in [
                    (a.solar_w_per_m2, b.solar_w_per_m2),
                    (a.albedo_w_per_m2, b.albedo_w_per_m2),
                    (a.earth_ir_w_per_m2, b.earth_ir_w_per_m2),
                ] {
                    assert!(
                        (x - y).abs() < 1e-9 * (1.0 + y.abs()),
                        "t {t}, θ {theta}, n {n:?}"
                    );
                }
            }
            let along = incident(&face([0.0, 0.0, 1.0], spin(false)), &e);
            let still = incident(&face([0.0, 0.0, 1.0], fixed), &e);
            assert!((along.solar_w_per_m2 - still.solar_w_per_m2).abs() < 1e-9);
            assert!((along.earth_ir_w_per_m2 - still.earth_ir_w_per_m2).abs() < 1e-9);
        }
    }
    let mean = incident(&face([1.0, 0.0, 0.0], spin(true)), &env(40.0, 0.0, 600e3));
    let want = 1361.0 / std::f64::consts::PI;
    assert!(
        (mean.solar_w_per_m2 - want).abs() < 1e-3 * want,
        "{} vs {want}",
        mean.solar_w_per_m2
    );
}

/// The albedo a face with LVLH normal `n` receives, by an independent method: a
/// surface integral over the visible cap of a Lambertian Earth (ground area elements,
/// cosines at both ends, 1/d²), not the solid-angle integral over the disc the code
/// uses.
fn albedo_by_surface_integral(n: [f64; 3], sun: [f64; 3], r: f64) -> f64 {
    let (a, s) = (0.3, 1361.0);
    let gamma_max = (R / r).acos();
    let (ng, np) = (120, 240);
    let (dg, dp) = (
        gamma_max / ng as f64,
        2.0 * std::f64::consts::PI / np as f64,
    );
    let mut sum = 0.0;
    for i in 0..ng {
        let g = (i as f64 + 0.5) * dg;
        let (sg, cg) = g.sin_cos();
        for j in 0..np {
            let (sp, cp) = ((j as f64 + 0.5) * dp).sin_cos();
            // ground normal; the Earth's centre at the origin, the spacecraft at −r ẑ
            let p = [sg * cp, sg * sp, -cg];
            let cos_zenith = p[0] * sun[0] + p[1] * sun[1] + p[2] * sun[2];
            if cos_zenith <= 0.0 {
                continue;
            }
            let d = [R * p[0], R * p[1], R * p[2] + r];
            let dd = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let cos_face = (n[0] * d[0] + n[1] * d[1] + n[2] * d[2]) / dd;
            let cos_ground = -(p[0] * d[0] + p[1] * d[1] + p[2] * d[2]) / dd;
            if cos_face <= 0.0 || cos_ground <= 0.0 {
                continue;
            }
            sum += a * s * cos_zenith / std::f64::consts::PI * cos_face * cos_ground / (dd * dd)
                * R
                * R
                * sg
                * dg
                * dp;
        }
    }
    sum
}

/// Orbit-averaged loads of a nadir-pointing cube (six unit faces, α = ε = 1) on a
/// circular orbit with a cylindrical shadow, against closed forms and a second method:
/// - direct Sun: S (cos β (6 − 2 cos a − 2 sin a) + 2a sin β) / 2π, the sunlit arc
///   being |θ| < a (from A (|sx| + |sy| + |sz|) of the projected cube);
/// - Earth infrared: q (F(0°) + 4 F(90°)), F(0°) = 1/H² and, for a plate whose normal
///   is tangent to the sphere, F(90°) = (atan(1/X) − X/H²)/π with X = √(H² − 1)
///   (Howell's catalog, plate tangent to a sphere);
/// - albedo: each face's orbit average within 1 % of the nadir face's peak of the
///   surface integral over the Earth's cap, and each face's RMS difference over the
///   orbit within 1.5 % of that peak (the aim the issue sets against industry tools).
#[test]
fn val_closed_form_orbit_averaged_cube() {
    let normals: [[f64; 3]; 6] = [
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
    ];
    // direct Sun and infrared at every sample, albedo at every 40th
    let (samples, every) = (7200, 40);
    for (h, beta) in [(500e3, 0.0f64), (500e3, 40.0), (1000e3, 70.0)] {
        let r = R + h;
        let hh = r / R;
        let b = beta.to_radians();
        // sunlit when cos θ cos β > 0 or the Sun's line misses the Earth's cylinder
        let cos_half = (1.0 - 1.0 / (hh * hh)).sqrt() / b.cos();
        let a = if cos_half >= 1.0 {
            std::f64::consts::PI
        } else {
            std::f64::consts::PI - cos_half.acos()
        };
        let (mut sun, mut ir) = (0.0, 0.0);
        let mut albedo = [0.0; 6];
        let mut truth = [0.0; 6];
        let mut sq = [0.0; 6];
        let mut peak: f64 = 0.0;
        for k in 0..samples {
            let theta = (k as f64 + 0.5) * 360.0 / samples as f64;
            let th = theta.to_radians();
            let lit =
                th.cos() * b.cos() > 0.0 || r * (1.0 - (th.cos() * b.cos()).powi(2)).sqrt() > R;
            let mut e = env(theta, beta, h);
            if !lit {
                e.solar_w_per_m2 = 0.0;
            }
            for (f, n) in normals.iter().enumerate() {
                let i = incident(&face(*n, NADIR), &e);
                sun += i.solar_w_per_m2;
                ir += i.earth_ir_w_per_m2;
                if k % every != every / 2 {
                    continue;
                }
                let t = albedo_by_surface_integral(*n, e.sun_lvlh, r);
                albedo[f] += i.albedo_w_per_m2;
                truth[f] += t;
                sq[f] += (i.albedo_w_per_m2 - t).powi(2);
                peak = peak.max(t);
            }
        }
        let n = samples as f64;
        let want_sun = 1361.0
            * (b.cos() * (6.0 - 2.0 * a.cos() - 2.0 * a.sin()) + 2.0 * a * b.sin())
            / (2.0 * std::f64::consts::PI);
        assert!(
            (sun / n - want_sun).abs() < 2e-3 * want_sun,
            "h {h}, β {beta}: Sun {} vs {want_sun}",
            sun / n
        );
        let x = (hh * hh - 1.0).sqrt();
        let side = ((1.0 / x).atan() - x / (hh * hh)) / std::f64::consts::PI;
        let want_ir = 237.0 * (1.0 / (hh * hh) + 4.0 * side);
        assert!(
            (ir / n - want_ir).abs() < 1e-9 * want_ir,
            "h {h}: IR {} vs {want_ir}",
            ir / n
        );
        let m = (samples / every) as f64;
        for f in 0..6 {
            let (got, want) = (albedo[f] / m, truth[f] / m);
            assert!(
                (got - want).abs() < 0.01 * peak,
                "h {h}, β {beta}, face {:?}: albedo {got} vs {want} (peak {peak})",
                normals[f]
            );
            let rms = (sq[f] / m).sqrt();
            eprintln!(
                "h {:.0} km, β {beta}°, face {:?}: albedo mean {got:.3} vs {want:.3} W/m², RMS {:.3} % of peak",
                h / 1e3,
                normals[f],
                100.0 * rms / peak
            );
            assert!(
                rms < 0.015 * peak,
                "h {h}, β {beta}, face {:?}: RMS {rms} of peak {peak}",
                normals[f]
            );
        }
    }
}
