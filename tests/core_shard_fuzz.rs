//! The shard reader against damaged and hostile files (issue 16, item 8): valid shard
//! files mutated many thousands of ways (bytes flipped, cut, repeated, numbers replaced
//! by extremes), each read, merged with its partner and reported. Nothing may panic,
//! abort or allocate without bound; a mutation either reads as a good shard or is
//! refused with an error naming the file.

use std::sync::atomic::AtomicU64;

use orbitlash::dispersion::{Plan, Sampling};
use orbitlash::io::scenario_toml::{REFERENCE_HINGE_TOML, parse_spec};
use orbitlash::margins::{
    Horizon, RunIdentity, SHARD_FORMAT, Shard, merge, read_shard, report, run_samples, shard_range,
};
use orbitlash::model::Model;
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
        let outcomes = run_samples(&model, &plan, range.clone(), horizon, &AtomicU64::new(0));
        serde_json::to_string(&Shard {
            format: SHARD_FORMAT.into(),
            run: id.clone(),
            shard: (i as u64, 2),
            range: (range.start, range.end),
            outcomes,
        })
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

/// One mutation of `text`.
fn mutate(text: &str, rng: &mut ChaCha8Rng) -> String {
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
    for case in 0..20_000 {
        let m = mutate(&a, &mut rng);
        let sb = sb.clone();
        let r = std::panic::catch_unwind(move || match read_shard(&m, "m.json") {
            Ok(s) => {
                if let Ok((id, all)) = merge(&[("m.json".into(), s), ("b.json".into(), sb)]) {
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
