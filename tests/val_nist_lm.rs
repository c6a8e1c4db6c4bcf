//! The bounded Levenberg–Marquardt of `diagnose` against NIST StRD nonlinear
//! regression problems with certified parameters, standard errors and residual sums
//! of squares (<https://www.itl.nist.gov/div898/strd/nls/nls_main.shtml>), from both
//! of NIST's start points, with the Jacobian by finite differences as `diagnose` uses
//! it.

use orbitlash::diagnose::lm::{LmOptions, minimize};

struct Certified {
    x: &'static [f64],
    y: &'static [f64],
    starts: [[f64; 2]; 2],
    b: [f64; 2],
    se: [f64; 2],
    ssr: f64,
}

/// Misra1a (lower difficulty): y = b1 (1 − exp(−b2 x)).
const MISRA1A: Certified = Certified {
    x: &[
        77.6, 114.9, 141.1, 190.8, 239.9, 289.0, 332.8, 378.4, 434.8, 477.3, 536.8, 593.1, 689.1,
        760.0,
    ],
    y: &[
        10.07, 14.73, 17.94, 23.93, 29.61, 35.18, 40.02, 44.82, 50.76, 55.05, 61.01, 66.40, 75.47,
        81.78,
    ],
    starts: [[500.0, 1e-4], [250.0, 5e-4]],
    b: [2.3894212918E+02, 5.5015643181E-04],
    se: [2.7070075241E+00, 7.2668688436E-06],
    ssr: 1.2455138894E-01,
};

/// BoxBOD (higher difficulty): the same model, six points, a start far away.
const BOXBOD: Certified = Certified {
    x: &[1.0, 2.0, 3.0, 5.0, 7.0, 10.0],
    y: &[109.0, 149.0, 149.0, 191.0, 213.0, 224.0],
    starts: [[1.0, 1.0], [100.0, 0.75]],
    b: [2.1380940889E+02, 5.4723748542E-01],
    se: [1.2354515176E+01, 1.0455993237E-01],
    ssr: 1.1680088766E+03,
};

fn check(name: &str, c: &Certified) {
    for start in c.starts {
        let f = |b: &[f64]| -> Result<Vec<f64>, ()> {
            Ok(c.x
                .iter()
                .zip(c.y)
                .map(|(x, y)| y - b[0] * (1.0 - (-b[1] * x).exp()))
                .collect())
        };
        let steps = [1e-7 * c.b[0], 1e-7 * c.b[1]];
        let fit = minimize(
            f,
            &start,
            &[-1e6, -10.0],
            &[1e6, 10.0],
            &steps,
            LmOptions::default(),
        )
        .unwrap();
        for i in 0..2 {
            let rel = (fit.x[i] - c.b[i]).abs() / c.b[i].abs();
            assert!(
                rel < 1e-6,
                "{name} from {start:?}: b{} = {} (certified {}, rel {rel:e})",
                i + 1,
                fit.x[i],
                c.b[i]
            );
            let se = fit.std_errors()[i];
            let rel = (se - c.se[i]).abs() / c.se[i];
            assert!(
                rel < 1e-3,
                "{name} from {start:?}: se(b{}) = {se} (certified {}, rel {rel:e})",
                i + 1,
                c.se[i]
            );
        }
        let rel = (fit.sum_squares - c.ssr).abs() / c.ssr;
        assert!(
            rel < 1e-8,
            "{name} from {start:?}: SSR {} (certified {})",
            fit.sum_squares,
            c.ssr
        );
        let r = fit.correlation();
        assert!((r[0][1] - r[1][0]).abs() < 1e-12 && r[0][1].abs() < 1.0);
    }
}

#[test]
fn val_nist_strd_misra1a_from_both_starts() {
    check("Misra1a", &MISRA1A);
}

#[test]
fn val_nist_strd_boxbod_from_both_starts() {
    check("BoxBOD", &BOXBOD);
}

/// Bounds hold: with b2 capped below its optimum the fit ends on the bound, reports
/// it, and has the least squares of b1 given that b2 (a linear problem, solved here in
/// closed form).
#[test]
fn val_closed_form_bounded_fit_ends_on_the_bound() {
    let c = &MISRA1A;
    let cap = 4e-4;
    let f = |b: &[f64]| -> Result<Vec<f64>, ()> {
        Ok(c.x
            .iter()
            .zip(c.y)
            .map(|(x, y)| y - b[0] * (1.0 - (-b[1] * x).exp()))
            .collect())
    };
    let fit = minimize(
        f,
        &[250.0, 3e-4],
        &[0.0, 0.0],
        &[1e4, cap],
        &[1e-5, 1e-11],
        LmOptions::default(),
    )
    .unwrap();
    assert_eq!(fit.x[1], cap);
    assert_eq!(fit.at_bound, vec![false, true]);
    let g: Vec<f64> = c.x.iter().map(|x| 1.0 - (-cap * x).exp()).collect();
    let b1 =
        g.iter().zip(c.y).map(|(g, y)| g * y).sum::<f64>() / g.iter().map(|g| g * g).sum::<f64>();
    assert!((fit.x[0] - b1).abs() / b1 < 1e-8, "{} vs {b1}", fit.x[0]);
}
