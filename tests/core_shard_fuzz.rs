//! The shard reader against damaged and hostile files (issue 16, item 8): valid shard
//! files mutated many thousands of ways (bytes flipped, cut, repeated, numbers replaced
//! by extremes), each read, merged with its partner and reported. Nothing may panic,
//! abort or allocate without bound; a mutation either reads as a good shard or is
//! refused with an error naming the file.

use std::sync::atomic::AtomicU64;

use orbitlash::io::scenario_toml::{REFERENCE_HINGE_TOML, parse_spec};
use orbitlash::margins::dispersion::{Plan, Sampling};
use orbitlash::margins::{
    Horizon, RunIdentity, SHARD_FORMAT, Shard, ShardLimits, merge, read_shard, report, run_samples,
    shard_range,
};
use orbitlash::spec::model::Model;
use rand_chacha::ChaCha8Rng;
use rand_chacha::rand_core::{Rng, SeedableRng};

/// Two shard files (text) of one small run.
fn shard_texts() -> [String; 2] {
    let text = format!(
        "{REFERENCE_HINGE_TOML}\n[[dispersion]]\npath = \"gear_pair.mesh.pinion.tooth_thinning_um\"\ndistribution = \"uniform\"\nmin = 16.0\nmax = 23.0\n\n[[dispersion]]\npath = \"environment.beta_deg\"\ndistribution = \"normal\"\nsd = 2.0\n"
    );
    let model = Model::new(parse_spec(&text, "f.toml").unwrap()).unwrap();
    let plan = Plan::new(&model, &model.spec().dispersion, Sampling::Random, 24, 5).unwrap();
    let horizon = Horizon::Orbits(0.2);
    let id = RunIdentity::new(&text, &[], model.scenario(), &plan, horizon);
    std::array::from_fn(|i| {
        let range = shard_range(24, i as u64, 2);
        let outcomes = run_samples(
            &model,
            &plan,
            range.clone(),
            horizon,
            u64::MAX,
            &AtomicU64::new(0),
        );
        serde_json::to_string(
            &Shard {
                format: SHARD_FORMAT.into(),
                run: id.clone(),
                shard: (i as u64, 2),
                range: (range.start, range.end),
                tool: "orbitlash test".into(),
                limits: ShardLimits::new(&model, &plan, horizon, range.clone()),
                outcomes,
                sha256: String::new(),
            }
            .sealed(),
        )
        .unwrap()
    })
}

const EXTREMES: [&str; 14] = [
    "-1",
    "0",
    "1",
    "-50",
    "1e308",
    "-1e308",
    "18446744073709551615",
    "4294967296",
    "1000000000000",
    "1e-320",
    "null",
    "true",
    "\"x\"",
    "[]",
];

/// A mutation at the level of the JSON: a shard that parses and may be consistent in
/// itself but differs from its partner (other pairs, names, minimums, sizes).
fn mutate_json(text: &str, rng: &mut ChaCha8Rng) -> String {
    let mut v: serde_json::Value = serde_json::from_str(text).unwrap();
    let pick = |rng: &mut ChaCha8Rng, n: usize| (rng.next_u64() % n.max(1) as u64) as usize;
    let outcomes = v["outcomes"].as_array().map_or(0, Vec::len);
    match rng.next_u64() % 9 {
        0 => {
            // another gear pair, in the header and in every outcome
            v["run"]["pairs"]
                .as_array_mut()
                .unwrap()
                .push(serde_json::json!(["mesh2", 5.0]));
            for o in v["outcomes"].as_array_mut().unwrap() {
                if let Some(p) = o["pairs"].as_array_mut()
                    && let Some(first) = p.first().cloned()
                {
                    p.push(first);
                }
            }
        }
        1 => v["run"]["pairs"] = serde_json::json!([]),
        2 => {
            let names = [
                "../x", "", "a b", "a\u{7}b", "mesh", "m/esh", "..", "ok-name",
            ];
            v["run"]["pairs"][0][0] = names[pick(rng, names.len())].into();
        }
        3 => {
            let names = ["../x", "", "r\u{1b}[0m", "other", "reference-hinge"];
            v["run"]["scenario"] = names[pick(rng, names.len())].into();
        }
        4 => v["run"]["pairs"][0][1] = [-1.0, 0.0, 1e7, 5.0, 20.0][pick(rng, 5)].into(),
        5 => {
            let k = pick(rng, outcomes);
            v["outcomes"][k]["invalid"] = ["bad", "x\u{1b}y"][pick(rng, 2)].into();
            v["outcomes"][k]["pairs"] = serde_json::json!([]);
        }
        6 => {
            v["run"]["dispersed"]
                .as_array_mut()
                .unwrap()
                .push("extra".into());
        }
        7 => {
            v["run"]["sets"] = serde_json::json!([["node.housing.capacitance_j_per_k", 130.0]]);
        }
        _ => {
            let k = pick(rng, outcomes);
            let field = [
                "min_backlash_um",
                "min_margin_um",
                "t_min_s",
                "orbit_phase_deg",
                "orbit_number",
            ][pick(rng, 5)];
            v["outcomes"][k]["pairs"][0][field] =
                [-1e300, -50.0, 0.0, 1e12, 400.0][pick(rng, 5)].into();
        }
    }
    v.to_string()
}

/// One mutation of `text`.
fn mutate(text: &str, rng: &mut ChaCha8Rng) -> String {
    if rng.next_u64().is_multiple_of(4) {
        return mutate_json(text, rng);
    }
    let mut b = text.as_bytes().to_vec();
    let n = b.len();
    let pick = |rng: &mut ChaCha8Rng, n: usize| (rng.next_u64() % n.max(1) as u64) as usize;
    match rng.next_u64() % 6 {
        0 => {
            // flip bytes
            for _ in 0..1 + rng.next_u64() % 4 {
                let i = pick(rng, n);
                b[i] ^= 1 << (rng.next_u64() % 8);
            }
        }
        1 => b.truncate(pick(rng, n)),
        2 => {
            // repeat a stretch
            let i = pick(rng, n);
            let j = (i + pick(rng, 200)).min(n);
            let piece = b[i..j].to_vec();
            b.splice(i..i, piece);
        }
        3 => {
            // delete a stretch
            let i = pick(rng, n);
            let j = (i + pick(rng, 50)).min(n);
            b.drain(i..j);
        }
        _ => {
            // replace a number by an extreme
            let starts: Vec<usize> = (1..n)
                .filter(|&i| {
                    (b[i].is_ascii_digit() || b[i] == b'-')
                        && matches!(b[i - 1], b':' | b',' | b'[')
                })
                .collect();
            if let Some(&i) = starts.get(pick(rng, starts.len())) {
                let mut j = i + 1;
                while j < n
                    && (b[j].is_ascii_digit() || matches!(b[j], b'.' | b'e' | b'E' | b'-' | b'+'))
                {
                    j += 1;
                }
                let with = EXTREMES[pick(rng, EXTREMES.len())];
                b.splice(i..j, with.bytes());
            }
        }
    }
    String::from_utf8_lossy(&b).into_owned()
}

#[test]
fn core_shard_reader_survives_mutation_fuzz() {
    let [a, b] = shard_texts();
    // the unmutated pair merges
    let sa = read_shard(&a, "a.json").unwrap();
    let sb = read_shard(&b, "b.json").unwrap();
    let (id, all) = merge(&[("a.json".into(), sa), ("b.json".into(), sb.clone())]).unwrap();
    assert_eq!(all.len(), 24);
    assert!(report(&id, &all).is_some());

    let mut rng = ChaCha8Rng::seed_from_u64(16);
    let (mut read, mut refused) = (0, 0);
    let sa = read_shard(&a, "a.json").unwrap();
    for case in 0..20_000 {
        // either shard mutated, merged in either order
        let second = rng.next_u64().is_multiple_of(2);
        let m = mutate(if second { &b } else { &a }, &mut rng);
        let other = if second { sa.clone() } else { sb.clone() };
        let flip = rng.next_u64().is_multiple_of(2);
        let r = std::panic::catch_unwind(move || match read_shard(&m, "m.json") {
            Ok(s) => {
                // sealed again, as a consistent forger would: merge and the report
                // then see the mutated numbers instead of refusing the checksum
                let s = s.sealed();
                let mut pair = vec![("m.json".to_string(), s), ("o.json".to_string(), other)];
                if flip {
                    pair.reverse();
                }
                if let Ok((id, all)) = merge(&pair) {
                    // what merged is one run: every outcome has a result per pair of it
                    assert!(
                        all.iter()
                            .all(|o| o.invalid.is_some() || o.pairs.len() == id.pairs.len())
                    );
                    let _ = report(&id, &all);
                }
                true
            }
            Err(e) => {
                assert!(e.to_string().contains("m.json"), "{e}");
                false
            }
        });
        match r {
            Ok(true) => read += 1,
            Ok(false) => refused += 1,
            Err(_) => panic!("mutation {case} panicked"),
        }
    }
    // the fuzz reached both sides: mutations that still read, and refusals
    assert!(
        read > 500 && refused > 5000,
        "{read} read, {refused} refused"
    );
}
