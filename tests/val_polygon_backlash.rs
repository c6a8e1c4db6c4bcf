//! The exact worst-case backlash against an independent 2-D computation: the two
//! gears' tooth outlines (involute flanks, radial flanks below the base circle, tip
//! arcs) are sampled densely, gear 1 is held at a phase, gear 2 is rotated one way and
//! the other until the outlines touch, and the smallest play over one base pitch of
//! gear 1 is the normal backlash.

use orbitlash::gear::backlash::{FlankGeometry, backlash};
use orbitlash::io::scenario_toml::reference;
use std::f64::consts::{PI, TAU};

#[derive(Clone, Copy)]
struct Outline {
    teeth: f64,
    rb: f64,
    sb: f64,
    ra: f64,
    rf: f64,
    cx: f64,
}

fn involute_polar_angle(rb: f64, r: f64) -> f64 {
    let a = (rb / r).acos();
    a.tan() - a
}

impl Outline {
    fn tau(&self) -> f64 {
        TAU / self.teeth
    }
    /// Half the angular width of a tooth at radius r.
    fn half_angle(&self, r: f64) -> f64 {
        let base = self.sb / (2.0 * self.rb);
        if r <= self.rb {
            base
        } else {
            base - involute_polar_angle(self.rb, r)
        }
    }
    /// Is the point inside the gear's material, with tooth 0 centred at angle `rot`?
    fn inside(&self, rot: f64, x: f64, y: f64) -> bool {
        let (dx, dy) = (x - self.cx, y);
        let r2 = dx * dx + dy * dy;
        if r2 > self.ra * self.ra {
            return false;
        }
        let r = r2.sqrt();
        if r < self.rf {
            return true;
        }
        let rel = dy.atan2(dx) - rot;
        let k = (rel / self.tau()).round();
        (rel - k * self.tau()).abs() <= self.half_angle(r)
    }
    /// Boundary points of the teeth whose centres lie within ±`window` of `towards`.
    fn boundary(&self, rot: f64, towards: f64, window: f64, n: usize) -> Vec<(f64, f64)> {
        let mut pts = Vec::new();
        let ua = (self.ra * self.ra / (self.rb * self.rb) - 1.0).sqrt();
        let arc = self.rb * ua * ua / 2.0;
        let kmin = ((towards - window - rot) / self.tau()).ceil() as i64;
        let kmax = ((towards + window - rot) / self.tau()).floor() as i64;
        let mut radii = Vec::new();
        for i in 0..=n {
            // uniform in involute arc length
            let u = (2.0 * arc * i as f64 / n as f64 / self.rb).sqrt();
            radii.push(self.rb * (1.0 + u * u).sqrt());
        }
        for i in 0..=n / 10 {
            radii.push(self.rf + (self.rb - self.rf) * i as f64 / (n / 10) as f64);
        }
        for k in kmin..=kmax {
            let c = rot + k as f64 * self.tau();
            for &r in &radii {
                let h = self.half_angle(r).max(0.0);
                for s in [-1.0, 1.0] {
                    let phi = c + s * h;
                    pts.push((self.cx + r * phi.cos(), r * phi.sin()));
                }
            }
            let h = self.half_angle(self.ra).max(0.0);
            for i in 0..=50 {
                let phi = c - h + 2.0 * h * i as f64 / 50.0;
                pts.push((self.cx + self.ra * phi.cos(), self.ra * phi.sin()));
            }
        }
        pts
    }
}

/// Smallest normal backlash over one base pitch of gear 1, by rotating gear 2 until
/// its outline touches gear 1's on either side.
fn polygon_backlash(g1: Outline, g2: Outline, phases: usize) -> f64 {
    let mut worst = f64::INFINITY;
    for ph in 0..phases {
        let u = (ph as f64 + 0.5) / phases as f64 * TAU * g1.rb / g1.teeth;
        let rot1 = u / g1.rb;
        let b1 = g1.boundary(rot1, 0.0, 1.6 * g1.tau(), 1000);
        // gear 2 turns clockwise by (u + w)/r_b2; w is the extra travel searched for.
        let rot2 = |w: f64| PI + g2.tau() / 2.0 - (u + w) / g2.rb;
        let overlap = |w: f64| {
            let r2 = rot2(w);
            let b2 = g2.boundary(r2, PI, 1.6 * g2.tau(), 1000);
            b2.iter().any(|&(x, y)| g1.inside(rot1, x, y))
                || b1.iter().any(|&(x, y)| g2.inside(r2, x, y))
        };
        assert!(
            !overlap(0.0),
            "the centred configuration overlaps at phase {ph}"
        );
        let touch = |dir: f64| {
            let (mut free, mut hit) = (0.0, dir * 1e-4);
            assert!(overlap(hit));
            while (hit - free).abs() > 1e-13 {
                let mid = 0.5 * (free + hit);
                if overlap(mid) { hit = mid } else { free = mid }
            }
            free
        };
        worst = worst.min(touch(1.0) - touch(-1.0));
    }
    worst
}

fn outlines(
    f1: FlankGeometry,
    f2: FlankGeometry,
    rf1: f64,
    rf2: f64,
    a: f64,
) -> (Outline, Outline) {
    (
        Outline {
            teeth: f1.teeth as f64,
            rb: f1.base_radius_m,
            sb: f1.base_thickness_m,
            ra: f1.tip_radius_m,
            rf: rf1,
            cx: 0.0,
        },
        Outline {
            teeth: f2.teeth as f64,
            rb: f2.base_radius_m,
            sb: f2.base_thickness_m,
            ra: f2.tip_radius_m,
            rf: rf2,
            cx: a,
        },
    )
}

/// The reference pair with each gear uniformly at its own temperature.
fn reference_at(pinion_k: f64, wheel_k: f64) -> (FlankGeometry, FlankGeometry, f64, f64, f64) {
    let sc = reference();
    let pair = &sc.gears[0];
    let mut temps = vec![pair.reference_temperature_k; sc.thermal.network.nodes.len()];
    for (g, t) in pair.gears.iter().zip([pinion_k, wheel_k]) {
        for &i in &g.nodes {
            temps[i] = t;
        }
    }
    let m = pair.evaluate(&temps).unwrap();
    let f = |k: usize| FlankGeometry {
        teeth: pair.gears[k].teeth,
        base_radius_m: m.gears[k].base_radius_m,
        base_thickness_m: m.gears[k].base_thickness_m,
        tip_radius_m: m.gears[k].tip_radius_m,
    };
    let scale = |k: usize| {
        m.gears[k].base_radius_m
            / pair.gears[k].base_radius_m(pair.module_m, pair.pressure_angle_rad)
    };
    (
        f(0),
        f(1),
        pair.gears[0].root_radius_m * scale(0),
        pair.gears[1].root_radius_m * scale(1),
        m.center_distance_m,
    )
}

fn check(pinion_k: f64, wheel_k: f64) -> f64 {
    let (f1, f2, rf1, rf2, a) = reference_at(pinion_k, wheel_k);
    let exact = backlash(&f1, &f2, a).unwrap().exact_m;
    let (o1, o2) = outlines(f1, f2, rf1, rf2, a);
    let poly = polygon_backlash(o1, o2, 24);
    eprintln!(
        "pinion {pinion_k} K, wheel {wheel_k} K: exact {:.5} µm, polygon {:.5} µm",
        exact * 1e6,
        poly * 1e6
    );
    assert!(
        (exact - poly).abs() < 0.01e-6,
        "pinion {pinion_k} K, wheel {wheel_k} K: exact {:.5} µm, polygon {:.5} µm",
        exact * 1e6,
        poly * 1e6
    );
    exact
}

#[test]
fn val_polygon_overlap_pinion_hotter() {
    // physics.md §4: pinion 40 K and wheel 10 K above 25 °C → 26.64 µm exact.
    let j = check(298.15 + 40.0, 298.15 + 10.0);
    assert!((j * 1e6 - 26.64).abs() < 0.005, "{} µm", j * 1e6);
}

#[test]
fn val_polygon_overlap_pinion_colder() {
    check(298.15 - 80.0, 298.15 - 20.0);
}

#[test]
fn val_polygon_overlap_equal_temperatures() {
    check(298.15 + 30.0, 298.15 + 30.0);
}
