//! Every registered technique's settings table: each default is a value its key takes, the canonical
//! string reads back to itself, and every key refuses what its kind does not take, with an error naming
//! the technique, the key and what it does take.

use shadow_core::technique::TechniqueSpec;
use shadow_core::technique::settings::SettingKind;
use shadowlab::TechniqueRegistry;

fn spec(name: &str, key: &str, value: &str) -> TechniqueSpec {
    TechniqueSpec { name: name.into(), values: vec![(key.into(), value.into())] }
}

#[test]
fn every_default_reads_back_to_itself() {
    let registry = TechniqueRegistry::builtin();
    for e in registry.entries() {
        let canonical = (e.canonical)(&TechniqueSpec::named(e.name)).unwrap();
        let given = shadow_core::technique::key_values(&canonical).unwrap();
        let again = (e.canonical)(&TechniqueSpec { name: e.name.into(), values: given }).unwrap();
        assert_eq!(canonical, again, "{}", e.name);
        let keys: Vec<_> = (e.keys)().iter().map(|k| k.key).collect();
        let listed: Vec<_> =
            canonical.split(',').filter(|p| !p.is_empty()).map(|p| p.split('=').next().unwrap()).collect();
        assert_eq!(keys, listed, "{}: the canonical string lists the keys in their order", e.name);
    }
}

#[test]
fn every_key_takes_its_bounds_and_refuses_past_them() {
    let registry = TechniqueRegistry::builtin();
    let mut checked = 0;
    for e in registry.entries() {
        for k in (e.keys)() {
            let ok = |v: &str| (e.canonical)(&spec(e.name, k.key, v));
            let (inside, outside): (Vec<String>, Vec<String>) = match k.kind {
                SettingKind::Int { lo, hi } => (
                    vec![lo.to_string(), hi.to_string()],
                    [lo.checked_sub(1), hi.checked_add(1)].into_iter().flatten().map(|v| v.to_string()).collect(),
                ),
                SettingKind::Float { lo, hi } => {
                    (vec![lo.to_string(), hi.to_string()], vec![(lo - 1.0).to_string(), (hi * 2.0 + 1.0).to_string()])
                }
                SettingKind::Choice(names) => (names.iter().map(|n| n.to_string()).collect(), vec!["nonsense".into()]),
            };
            for v in &inside {
                // A cross-field check may refuse a bound (theta_high below the default theta_low): only the
                // key's own kind is checked here.
                if let Err(err) = ok(v) {
                    assert!(!err.to_string().contains(&k.expected()), "{}: {err}", e.name);
                }
            }
            for v in &outside {
                let err = ok(v).expect_err(&format!("{} {}={v}", e.name, k.key)).to_string();
                assert!(err.contains(e.name) && err.contains(k.key) && err.contains(&k.expected()), "{err}");
            }
            checked += 1;
        }
    }
    assert!(checked >= 40, "only {checked} keys");
}
