//! Margin and interference events follow the backlash evaluated at every step.

use orbitlash::io::scenario_toml::{REFERENCE_HINGE_TOML, parse};
use orbitlash::run::sim::{Event, EventKind, Observer, ObserverResult, StepView, simulate};

#[derive(Default)]
struct Trace {
    steps: Vec<(f64, f64)>,
    events: Vec<Event>,
}

impl Observer for Trace {
    fn on_step(&mut self, s: &StepView<'_>) -> ObserverResult {
        self.steps.push((s.t1_s(), s.mesh[0].backlash_exact_m));
        Ok(())
    }
    fn on_event(&mut self, e: &Event) -> ObserverResult {
        self.events.push(*e);
        Ok(())
    }
}

#[test]
fn core_heating_the_pinion_closes_the_backlash_and_reports_it() {
    // 40 W dissipated in the pinion rim from t = 0: it heats far above the wheel.
    let text = REFERENCE_HINGE_TOML.replacen(
        "[[sensor]]",
        "[[dissipation]]\nnode = \"gear1.r2\"\npower_w = 40.0\n\n[[sensor]]",
        1,
    );
    let sc = parse(&text, "<heated pinion>").unwrap();
    let mut trace = Trace::default();
    simulate(
        &sc.thermal,
        &sc.gears,
        &sc.solver,
        2.0 * sc.period_s(),
        &mut trace,
        None,
    )
    .unwrap();
    let first =
        |k: fn(usize) -> EventKind| trace.events.iter().find(|e| e.kind == k(0)).map(|e| e.t_s);
    let margin_low = first(EventKind::MarginLow).expect("margin event");
    let interference = first(EventKind::InterferenceStart).expect("interference event");
    assert!(margin_low < interference);
    let at = |t: f64| trace.steps.iter().position(|s| s.0 == t).unwrap();
    let (i, j) = (at(margin_low), at(interference));
    let min_allowed = sc.gears[0].min_backlash_m;
    assert!(trace.steps[i].1 < min_allowed && trace.steps[i - 1].1 >= min_allowed);
    assert!(trace.steps[j].1 <= 0.0 && trace.steps[j - 1].1 > 0.0);
}
