//! The core as a library for many runs (issue 9): a setup built once, runs from an
//! explicit state. A run split at any step and resumed from its end state gives the
//! unsplit run's numbers bit for bit (on the same setup or a new one); a heater inside
//! its hysteresis band can start on; the stepping loop does not allocate.

use std::alloc::{GlobalAlloc, Layout, System};

use orbitlash::io::scenario_toml;
use orbitlash::run::sample::{Cadence, Sampler, Want};
use orbitlash::run::sim::{
    Event, EventKind, Observer, ObserverResult, RunStart, RunStats, Setup, State, StepView, Stop,
};
use orbitlash::spec::scenario::Scenario;

/// Counts the allocations of the current thread (tests run on several), to show the
/// stepping loop makes none.
struct Counting;
thread_local! {
    static ALLOCATIONS: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}
fn allocations() -> u64 {
    ALLOCATIONS.with(|c| c.get())
}
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        // (a thread-local without destructor: safe to touch while allocating)
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        unsafe { System.alloc(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        unsafe { System.dealloc(p, l) }
    }
}
#[global_allocator]
static GLOBAL: Counting = Counting;

/// Every accepted step's end time, temperatures and heater states, and every event
/// (kind and time), bit for bit.
#[derive(Default)]
struct Record(Vec<(f64, Vec<f64>)>, Vec<(EventKind, u64)>);

impl Observer for Record {
    fn on_step(&mut self, s: &StepView<'_>) -> ObserverResult {
        let mut v = s.temps1_k().to_vec();
        v.extend(s.heaters_on.iter().map(|&h| if h { 1.0 } else { 0.0 }));
        self.0.push((s.t1_s(), v));
        Ok(())
    }
    fn on_event(&mut self, e: &Event) -> ObserverResult {
        self.1.push((e.kind, e.t_s.to_bits()));
        Ok(())
    }
}

fn scenario(file: &str) -> Scenario {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(file);
    scenario_toml::load_file(&path).unwrap().0
}

fn unsplit(sc: &Scenario, t_end: f64) -> (Record, State) {
    let mut setup = Setup::new(&sc.thermal, &sc.gears, &sc.solver);
    let mut state = setup.initial_state();
    let mut rec = Record::default();
    setup
        .run(&mut state, t_end, &mut rec, Stop::default())
        .unwrap();
    (rec, state)
}

/// Runs to the end of step `k` of the unsplit run, then resumes (on the same setup, or
/// on a new one) to the end; the steps must be the unsplit run's, bit for bit.
fn split_at(sc: &Scenario, t_end: f64, whole: &Record, k: usize, new_setup: bool) {
    let mut setup = Setup::new(&sc.thermal, &sc.gears, &sc.solver);
    let mut state = setup.initial_state();
    let mut first = Record::default();
    let stop = Stop {
        pause_after_s: Some(whole.0[k].0),
        ..Stop::default()
    };
    let stats = setup.run(&mut state, t_end, &mut first, stop).unwrap();
    assert!(stats.paused);
    assert_eq!(first.0.len(), k + 1);
    let mut second = Record::default();
    if new_setup {
        let mut other = Setup::new(&sc.thermal, &sc.gears, &sc.solver);
        other
            .run(&mut state, t_end, &mut second, Stop::default())
            .unwrap();
    } else {
        setup
            .run(&mut state, t_end, &mut second, Stop::default())
            .unwrap();
    }
    let events: Vec<_> = first.1.into_iter().chain(second.1).collect();
    assert_eq!(events, whole.1, "split at step {k}: events");
    let joined: Vec<_> = first.0.into_iter().chain(second.0).collect();
    assert_eq!(joined.len(), whole.0.len(), "split at step {k}: step count");
    for (i, (a, b)) in joined.iter().zip(&whole.0).enumerate() {
        assert!(
            a.0.to_bits() == b.0.to_bits() && a.1 == b.1,
            "split at step {k} (new setup: {new_setup}): step {i} differs: t {} vs {}",
            a.0,
            b.0
        );
    }
}

#[test]
fn core_split_runs_are_bit_identical() {
    // the reference (eclipses, load kinks) and the 90-day profile (heater, modes,
    // profile tables, albedo and IR), over stretches with every kind of event
    for (file, t_end) in [
        ("reference-hinge.toml", 3.0 * 5676.978),
        ("hinge-90-day-drift.toml", 3.0 * 86400.0),
    ] {
        let sc = scenario(file);
        let (whole, end) = unsplit(&sc, t_end);
        let n = whole.0.len();
        for k in [0, 1, 7, n / 3, n / 2, n - 2] {
            split_at(&sc, t_end, &whole, k, false);
            split_at(&sc, t_end, &whole, k, true);
        }
        // the end state resumes the same way as one run further
        let mut setup = Setup::new(&sc.thermal, &sc.gears, &sc.solver);
        let mut a = end.clone();
        let mut b = end;
        b.forget_solver();
        let sa = setup
            .run(&mut a, t_end + 4000.0, &mut (), Stop::default())
            .unwrap();
        let sb = setup
            .run(&mut b, t_end + 4000.0, &mut (), Stop::default())
            .unwrap();
        assert!(sa.steps > 0 && sb.steps > 0);
        // a resumed state and a fresh one at the same temperatures agree to the
        // tolerance (not bits: the solver's memory differs)
        for (x, y) in a.temperatures_k.iter().zip(&b.temperatures_k) {
            assert!((x - y).abs() < 0.01, "{file}: {x} vs {y}");
        }
    }
}

#[test]
fn core_energy_balance_is_measured_from_the_start_state() {
    let sc = scenario("hinge-90-day-drift.toml");
    let mut setup = Setup::new(&sc.thermal, &sc.gears, &sc.solver);
    let mut state = setup.initial_state();
    let first: RunStats = setup
        .run(&mut state, 86400.0, &mut (), Stop::default())
        .unwrap();
    let second = setup
        .run(&mut state, 2.0 * 86400.0, &mut (), Stop::default())
        .unwrap();
    for s in [&first, &second] {
        assert!(s.energy.relative_error() < 1e-5, "{:?}", s.energy);
    }
    assert_eq!(second.t_start_s, 86400.0);
    assert!(second.energy.stored_j.abs() < 0.1 * second.energy.absorbed_j);
}

#[test]
fn core_a_heater_inside_its_band_can_start_on() {
    // The 90-day profile's housing heater switches on at −10 °C and off at −5 °C. Start
    // the housing inside the band: derived from the temperature the heater is off; set
    // on, it heats from t = 0 until the housing reaches −5 °C, and the energy balance
    // shows exactly its power times that time more dissipated (the motor's schedule
    // does not depend on temperatures).
    let sc = scenario("hinge-90-day-drift.toml");
    let net = &sc.thermal.network;
    let heater = &net.heaters[0];
    let mut temps = net.initial_temperatures_k();
    temps[heater.sensor_node] = 0.5 * (heater.on_k + heater.off_k);
    let mut setup = Setup::new(&sc.thermal, &sc.gears, &sc.solver);
    let derived = setup.state_at(0.0, temps.clone());
    assert!(!derived.heaters_on[0], "inside the band, off by default");
    let t_end = 600.0;
    #[derive(Default)]
    struct HeaterEvents(Vec<(f64, EventKind)>);
    impl Observer for HeaterEvents {
        fn on_event(&mut self, e: &Event) -> ObserverResult {
            if matches!(e.kind, EventKind::HeaterOn(_) | EventKind::HeaterOff(_)) {
                self.0.push((e.t_s, e.kind));
            }
            Ok(())
        }
    }
    let run = |on: bool, setup: &mut Setup<'_>| {
        let mut s = setup.state_at(0.0, temps.clone());
        s.heaters_on[0] = on;
        let mut ev = HeaterEvents::default();
        let stats = setup.run(&mut s, t_end, &mut ev, Stop::default()).unwrap();
        (stats.energy.dissipated_j, ev.0)
    };
    let (off, events_off) = run(false, &mut setup);
    let (on, events_on) = run(true, &mut setup);
    assert!(events_off.is_empty(), "{events_off:?}");
    let (t_off, kind) = events_on[0];
    assert_eq!(kind, EventKind::HeaterOff(0));
    assert!(t_off > 0.0);
    assert!(
        (on - off - heater.power_w * t_off).abs() < 1e-6 * on,
        "heater on until {t_off} s: {on} J vs {off} J dissipated"
    );
    // and a run split while it is on and inside the band resumes identically
    let mut s = setup.state_at(0.0, temps.clone());
    s.heaters_on[0] = true;
    let mut whole = Record::default();
    let mut a = s.clone();
    setup
        .run(&mut a, t_end, &mut whole, Stop::default())
        .unwrap();
    let mut first = Record::default();
    let mut b = s;
    let stop = Stop {
        pause_after_s: Some(whole.0[3].0),
        ..Stop::default()
    };
    setup.run(&mut b, t_end, &mut first, stop).unwrap();
    assert!(b.heaters_on[0]);
    let mut second = Record::default();
    setup
        .run(&mut b, t_end, &mut second, Stop::default())
        .unwrap();
    let events: Vec<_> = first.1.into_iter().chain(second.1).collect();
    assert_eq!(events, whole.1, "heater in its band: events");
    let joined: Vec<_> = first.0.into_iter().chain(second.0).collect();
    assert_eq!(joined, whole.0);
}

#[test]
fn core_the_stepping_loop_does_not_allocate() {
    let sc = scenario("hinge-90-day-drift.toml");
    let mut setup = Setup::new(&sc.thermal, &sc.gears, &sc.solver);
    let count = |setup: &mut Setup<'_>, days: f64| {
        let mut state = setup.initial_state();
        let before = allocations();
        let stats = setup
            .run(&mut state, days * 86400.0, &mut (), Stop::default())
            .unwrap();
        (allocations() - before, stats.steps)
    };
    count(&mut setup, 1.0); // the first run sizes the workspace's buffers
    let (short, short_steps) = count(&mut setup, 1.0);
    let (long, long_steps) = count(&mut setup, 5.0);
    assert!(long_steps > 4 * short_steps);
    // a run allocates its start and end (the state, the statistics), never per step
    assert_eq!(
        long, short,
        "{short} allocations for {short_steps} steps, {long} for {long_steps}"
    );
}

/// Sums what it samples (so that the samples are used).
struct Sampled(Sampler, f64, u64);

impl Observer for Sampled {
    fn on_start(&mut self, r: &RunStart<'_>) -> ObserverResult {
        if let Some(s) = self.0.start(r) {
            self.1 += s.temperatures_k[0];
            self.2 += 1;
        }
        Ok(())
    }
    fn on_step(&mut self, step: &StepView<'_>) -> ObserverResult {
        let (sum, n) = (&mut self.1, &mut self.2);
        self.0.each(step, |s| {
            *sum += s.temperatures_k[0] + s.flows.absorbed_w + s.mesh[0].backlash_exact_m;
            *n += 1;
            Ok::<_, std::convert::Infallible>(())
        })?;
        Ok(())
    }
}

#[test]
fn core_sampling_does_not_allocate_per_sample() {
    let sc = scenario("hinge-90-day-drift.toml");
    let mut setup = Setup::new(&sc.thermal, &sc.gears, &sc.solver);
    for cadence in [Cadence::Steps(1), Cadence::Interval(7.0)] {
        let mut obs = Sampled(Sampler::new(cadence.clone(), Want::ALL), 0.0, 0);
        let mut count = |days: f64| {
            let mut state = setup.initial_state();
            obs.2 = 0;
            let before = allocations();
            setup
                .run(&mut state, days * 86400.0, &mut obs, Stop::default())
                .unwrap();
            (allocations() - before, obs.2)
        };
        count(1.0); // sizes the sample's buffers
        let (short, short_samples) = count(1.0);
        let (long, long_samples) = count(5.0);
        assert!(long_samples > 4 * short_samples && obs.1.is_finite());
        assert_eq!(
            long, short,
            "{cadence:?}: {short} allocations for {short_samples} samples, {long} for {long_samples}"
        );
    }
}

/// Runs `state` on `setup` to `t_end` and returns the record.
fn record(setup: &mut Setup<'_>, state: &mut State, t_end: f64) -> Record {
    let mut r = Record::default();
    setup.run(state, t_end, &mut r, Stop::default()).unwrap();
    r
}

#[test]
fn core_a_changed_state_or_model_drops_the_solver_memory() {
    // The solver's memory belongs to the state a run left and to its model: a state
    // edited by hand (shooting sets new temperatures) or run on another model starts as
    // a fresh state would, bit for bit.
    let sc = scenario("reference-hinge.toml");
    let period = sc.period_s();
    let mut setup = Setup::new(&sc.thermal, &sc.gears, &sc.solver);
    let mut state = setup.initial_state();
    setup
        .run(&mut state, 0.7 * period, &mut (), Stop::default())
        .unwrap();
    assert!(state.is_resumed());

    let mut edited = state.clone();
    edited.temperatures_k[0] += 1.0;
    let mut fresh = edited.clone();
    fresh.forget_solver();
    let a = record(&mut setup, &mut edited, 1.5 * period);
    let b = record(&mut setup, &mut fresh, 1.5 * period);
    assert_eq!(a.0, b.0, "an edited state resumes as a fresh one");

    let mut moved = state.clone();
    moved.t_s += 10.0;
    let mut fresh = moved.clone();
    fresh.forget_solver();
    assert_eq!(
        record(&mut setup, &mut moved, 1.5 * period).0,
        record(&mut setup, &mut fresh, 1.5 * period).0,
        "a state moved in time resumes as a fresh one"
    );

    // Another model (a heavier housing): its setup ignores the memory.
    let mut heavier = sc.clone();
    heavier.thermal.network.nodes[0].capacitance_j_per_k *= 1.5;
    let mut other = Setup::new(&heavier.thermal, &heavier.gears, &heavier.solver);
    let mut carried = state.clone();
    let mut fresh = state.clone();
    fresh.forget_solver();
    assert_eq!(
        record(&mut other, &mut carried, 1.5 * period).0,
        record(&mut other, &mut fresh, 1.5 * period).0,
        "another model starts fresh"
    );
    // The same model on a new setup keeps it (the split test shows it bit for bit).
    let mut same = Setup::new(&sc.thermal, &sc.gears, &sc.solver);
    let mut carried = state.clone();
    let mut fresh = state.clone();
    fresh.forget_solver();
    assert_ne!(
        record(&mut same, &mut carried, 1.5 * period).0,
        record(&mut same, &mut fresh, 1.5 * period).0,
        "the same model keeps the memory"
    );
}

#[test]
fn core_an_observer_that_fails_at_the_start_leaves_the_state() {
    struct Refuses;
    impl Observer for Refuses {
        fn on_start(&mut self, _r: &RunStart<'_>) -> ObserverResult {
            Err("no".into())
        }
    }
    let sc = scenario("reference-hinge.toml");
    let mut setup = Setup::new(&sc.thermal, &sc.gears, &sc.solver);
    let mut state = setup.initial_state();
    setup
        .run(&mut state, 1000.0, &mut (), Stop::default())
        .unwrap();
    let before = state.clone();
    assert!(
        setup
            .run(&mut state, 2000.0, &mut Refuses, Stop::default())
            .is_err()
    );
    assert_eq!(state.t_s, before.t_s);
    assert_eq!(state.temperatures_k, before.temperatures_k);
    assert_eq!(state.heaters_on, before.heaters_on);
    // and it runs on
    setup
        .run(&mut state, 2000.0, &mut (), Stop::default())
        .unwrap();
}

#[test]
fn core_sensor_readings_continue_across_a_split_run() {
    use orbitlash::run::sensor::Readings;
    let mut sc = scenario("reference-hinge.toml");
    sc.sensors[0].tau_s = 600.0;
    sc.sensors[1].offset_k = 0.5;
    let t_end = 1.5 * sc.period_s();
    for cadence in [Cadence::Interval(30.0), Cadence::Steps(3)] {
        let mut setup = Setup::new(&sc.thermal, &sc.gears, &sc.solver);
        let mut whole = Readings::new(sc.sensors.clone(), cadence.clone());
        let mut state = setup.initial_state();
        setup
            .run(&mut state, t_end, &mut whole, Stop::default())
            .unwrap();
        let mut split = Readings::new(sc.sensors.clone(), cadence.clone());
        let mut state = setup.initial_state();
        let stop = Stop {
            pause_after_s: Some(0.6 * sc.period_s()),
            ..Stop::default()
        };
        setup.run(&mut state, t_end, &mut split, stop).unwrap();
        setup
            .run(&mut state, t_end, &mut split, Stop::default())
            .unwrap();
        assert_eq!(split.times_s, whole.times_s, "{cadence:?}: times");
        assert_eq!(split.values, whole.values, "{cadence:?}: readings");
        // a fresh start (another time) begins afresh
        let mut again = setup.initial_state();
        setup
            .run(&mut again, 1000.0, &mut split, Stop::default())
            .unwrap();
        assert_eq!(split.times_s[0], 0.0);
        assert!(*split.times_s.last().unwrap() <= 1000.0);
    }
}
