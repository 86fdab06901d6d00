//! The scene runner (`examples/scenes`) through its own command-line entry point: every scene,
//! briefly, in both dimensions, with every model; each JSON line must carry the documented keys
//! with the documented types (issue 5, acceptance 1).

#[path = "../examples/scenes/cli.rs"]
mod cli;

use serde_json::Value;

/// Keys every line carries, with their JSON type: "s" string, "u" unsigned integer, "f" number,
/// "f?" number or null, "b" boolean, "b?" boolean or null, "s?" string or null.
const KEYS: &[(&str, &str)] = &[
    ("scene", "s"),
    ("dim", "u"),
    ("model", "s"),
    ("iterations", "s?"),
    ("integrator", "s?"),
    ("sweeps", "u?"),
    ("res", "u"),
    ("nodes", "u"),
    ("elements", "u"),
    ("dt", "f"),
    ("max_substeps", "u"),
    ("substeps", "f"),
    ("substep_mode", "s"),
    ("sim_s", "f"),
    ("wall_s", "f"),
    ("wall_per_sim_s", "f"),
    ("mass", "f?"),
    ("young", "f"),
    ("poisson", "f"),
    ("k_over_m", "f?"),
    ("bounce_apex_com", "f?"),
    ("rest_com", "f?"),
    ("max_penetration", "f?"),
    ("min_vol_ratio", "f"),
    ("max_inverted_elements", "u"),
    ("final_inverted_elements", "u"),
    ("failed", "b"),
    ("failure", "s?"),
    ("first_failure", "f?"),
    ("shape_error", "f?"),
    ("loaded_volume_ratio", "f?"),
    ("spurious_mean", "f?"),
    ("spurious_std", "f?"),
    ("spurious_max", "f?"),
    ("max_anchor_error", "f?"),
    ("max_self_penetration", "f?"),
    ("bodies", "u?"),
    ("max_interpenetration", "f?"),
    ("rest_interpenetration", "f?"),
    ("energy_gain", "f?"),
    ("energy_over_start", "f?"),
    ("energy_change", "f?"),
    ("scatter", "f?"),
    ("top_height_ratio", "f?"),
    ("asleep", "b?"),
    ("slip", "f?"),
    ("overspeed", "f?"),
    ("step_spike", "f?"),
    ("final_speed", "f?"),
    ("pairs_wall_s", "f?"),
    ("measured_poisson", "f?"),
    ("measured_young_modulus", "f?"),
    ("measured_frequency", "f?"),
    ("theory_frequency", "f?"),
    ("measured_damping_ratio", "f?"),
    ("sag", "f?"),
    ("sag_theory", "f?"),
    ("sag_error", "f?"),
    ("sag_wobble", "f?"),
    ("inflation", "f?"),
    ("gas_volume_ratio", "f?"),
    ("boyle_error", "f?"),
    ("recovery_error", "f?"),
    ("torn_at_strain", "f?"),
    ("pieces", "u?"),
    ("kept_bend", "f?"),
    ("kept_bend_theory", "f?"),
    ("dent", "f?"),
    ("final_kinetic_energy", "f"),
    ("nan", "b"),
    ("exploded", "b"),
];

fn type_ok(v: &Value, t: &str) -> bool {
    match t {
        "s" => v.is_string(),
        "s?" => v.is_string() || v.is_null(),
        "u" => v.is_u64(),
        "u?" => v.is_u64() || v.is_null(),
        "f" => v.is_number(),
        "f?" => v.is_number() || v.is_null(),
        "b" => v.is_boolean(),
        "b?" => v.is_boolean() || v.is_null(),
        _ => false,
    }
}

/// Runs the runner with `args` and returns its JSON lines, checked key by key.
fn run(args: &[&str]) -> Vec<serde_json::Map<String, Value>> {
    let mut argv = vec!["scenes"];
    argv.extend_from_slice(args);
    argv.push("--json");
    let mut out = Vec::new();
    let records = cli::run(argv.clone(), &mut out).unwrap_or_else(|e| panic!("{argv:?}: {e}"));
    let text = String::from_utf8(out).expect("utf-8 output");
    let lines: Vec<_> = text.lines().collect();
    assert_eq!(lines.len(), records.len(), "one line per run");
    assert!(!lines.is_empty(), "{argv:?} printed nothing");
    lines
        .iter()
        .map(|line| {
            let v: Value = serde_json::from_str(line).unwrap_or_else(|e| panic!("{line}: {e}"));
            let obj = v.as_object().expect("one object per line").clone();
            for (key, t) in KEYS {
                let value = obj
                    .get(*key)
                    .unwrap_or_else(|| panic!("{argv:?}: key {key} missing in {line}"));
                assert!(type_ok(value, t), "{argv:?}: {key} = {value} is not {t}");
            }
            assert_eq!(obj.len(), KEYS.len(), "unexpected keys in {line}");
            obj
        })
        .collect()
}

fn models(lines: &[serde_json::Map<String, Value>]) -> Vec<String> {
    let mut m: Vec<String> = lines
        .iter()
        .map(|l| l["model"].as_str().unwrap().to_string())
        .collect();
    m.dedup();
    m
}

#[test]
fn fall_runs_every_model_in_both_dimensions() {
    let lines = run(&["fall", "--res", "3", "--seconds", "0.05"]);
    let all = models(&lines);
    for m in [
        "springs",
        "edge-repulsion",
        "shape-matching",
        "rapier-volume",
        "rapier-corotational",
        "rapier-neo-hookean",
    ] {
        assert!(all.iter().any(|x| x == m), "{m} missing from {all:?}");
    }
    let dims: Vec<u64> = lines.iter().map(|l| l["dim"].as_u64().unwrap()).collect();
    assert!(dims.contains(&2) && dims.contains(&3));
    for l in &lines {
        assert_eq!(l["scene"], "fall");
        assert!(l["rest_com"].is_number() && l["max_penetration"].is_number());
        assert!((l["sim_s"].as_f64().unwrap() - 0.05).abs() < 1e-6);
        // A 50 ms fall from 2 m: nothing touches the ground, nothing deforms much.
        assert_eq!(l["max_inverted_elements"], 0, "{l:?}");
        assert!(l["first_failure"].is_null() && l["shape_error"].is_null());
    }
}

#[test]
fn limb_reports_the_angle_of_failure() {
    let lines = run(&[
        "limb",
        "--res",
        "5",
        "--seconds",
        "0.3",
        "--model",
        "springs",
        "rapier-volume",
    ]);
    assert_eq!(lines.len(), 4, "two models, two dimensions");
    for l in &lines {
        assert_eq!(l["scene"], "limb");
        assert!(l["max_anchor_error"].is_number());
        assert!((l["sim_s"].as_f64().unwrap() - 0.3).abs() < 1e-4);
    }
}

#[test]
fn crush_sweeps_masses_and_measures_recovery() {
    let lines = run(&[
        "crush",
        "--res",
        "3",
        "--seconds",
        "0.2",
        "--mass",
        "1",
        "1000",
        "--model",
        "edge-repulsion",
        "rapier-corotational",
    ]);
    assert_eq!(lines.len(), 8, "two masses, two models, two dimensions");
    for l in &lines {
        assert_eq!(l["scene"], "crush");
        assert!(l["mass"].is_number() && l["shape_error"].is_number());
        assert!(l["loaded_volume_ratio"]
            .as_f64()
            .is_some_and(|v| v > 0.0 && v < 1.0));
    }
}

#[test]
fn the_tear_scene_pulls_a_slab_into_two_pieces_beside_rapiers() {
    let lines = run(&[
        "tear",
        "--dim",
        "2",
        "--model",
        "edge-repulsion",
        "rapier-corotational",
    ]);
    assert_eq!(lines.len(), 2);
    for l in &lines {
        assert_eq!(l["scene"], "tear");
        assert!(l["torn_at_strain"]
            .as_f64()
            .is_some_and(|s| (s - 0.1).abs() <= 0.01));
        assert_eq!(l["pieces"], 2, "{l:?}");
    }
}

#[test]
fn the_balloon_squeezes_sinews_gas_and_rapiers_volume_target() {
    let lines = run(&[
        "balloon",
        "--dim",
        "2",
        "--model",
        "edge-repulsion",
        "rapier-corotational",
    ]);
    assert_eq!(lines.len(), 2);
    for l in &lines {
        assert_eq!(l["scene"], "balloon");
        assert!(l["gas_volume_ratio"].as_f64().is_some_and(|v| v < 0.72));
        assert!(l["inflation"].as_f64().is_some_and(|v| v > 1.0));
    }
    let sinew = lines
        .iter()
        .find(|l| l["model"] == "edge-repulsion")
        .unwrap();
    assert!(sinew["boyle_error"].as_f64().is_some_and(|e| e < 0.02));
    assert_eq!(sinew["failed"], false, "{sinew:?}");
    let rapier = lines
        .iter()
        .find(|l| l["model"] != "edge-repulsion")
        .unwrap();
    assert!(rapier["boyle_error"].is_null(), "rapier has no gas");
}

#[test]
fn manipulator_counts_strikes() {
    let lines = run(&[
        "manipulator",
        "--res",
        "3",
        "--strikes",
        "2",
        "--seconds",
        "0.2",
        "--model",
        "shape-matching",
        "--iterations",
        "1",
        "polar",
    ]);
    assert_eq!(lines.len(), 4);
    let fits: Vec<&str> = lines
        .iter()
        .map(|l| l["iterations"].as_str().unwrap())
        .collect();
    assert_eq!(fits, ["1", "polar", "1", "polar"]);
    for l in &lines {
        assert!(l["shape_error"].is_number());
    }
}

#[test]
fn dt_sweep_runs_fixed_then_automatic_substeps() {
    let lines = run(&[
        "dt-sweep",
        "--dim",
        "2",
        "--res",
        "3",
        "--seconds",
        "0.05",
        "--model",
        "springs",
    ]);
    let modes: Vec<&str> = lines
        .iter()
        .map(|l| l["substep_mode"].as_str().unwrap())
        .collect();
    assert_eq!(
        modes,
        ["fixed"; 5]
            .into_iter()
            .chain(["auto"; 5])
            .collect::<Vec<_>>()
    );
    let dts: Vec<f64> = lines
        .iter()
        .take(5)
        .map(|l| l["dt"].as_f64().unwrap() * 1e3)
        .collect();
    for (dt, want) in dts.iter().zip([0.5, 1.0, 2.0, 5.0, 16.7]) {
        assert!((dt - want).abs() < 1e-3, "dt {dt} ms, want {want}");
    }
    for l in lines.iter().take(5) {
        assert_eq!(l["substeps"], 1.0, "fixed mode takes one substep per step");
    }
}

#[test]
fn rotation_error_reports_the_spread() {
    let lines = run(&["rotation-error", "--k-over-m", "1e4", "--seconds", "0.3"]);
    assert_eq!(lines.len(), 10, "five rows, two dimensions");
    for l in &lines {
        assert_eq!(l["model"], "shape-matching");
        assert!(l["spurious_mean"].as_f64().unwrap() >= 0.0);
        assert!(l["spurious_max"].as_f64().unwrap() >= l["spurious_mean"].as_f64().unwrap());
    }
}

#[test]
fn the_implicit_integrator_is_chosen_from_the_command_line() {
    let lines = run(&[
        "fall",
        "--dim",
        "3",
        "--res",
        "3",
        "--seconds",
        "0.1",
        "--dt",
        "0.0166667",
        "--model",
        "edge-repulsion",
        "rapier-volume",
        "--integrator",
        "implicit",
        "--sweeps",
        "4",
    ]);
    assert_eq!(lines[0]["integrator"], "implicit");
    assert_eq!(lines[0]["sweeps"], 4);
    assert!(lines[0]["substeps"].as_f64().unwrap() <= 1.0);
    assert!(lines[1]["integrator"].is_null() && lines[1]["sweeps"].is_null());
}

#[test]
fn the_multi_body_scenes_take_and_record_the_integrator() {
    let lines = run(&[
        "pile",
        "--dim",
        "2",
        "--bodies",
        "2",
        "--seconds",
        "0.1",
        "--model",
        "edge-repulsion",
        "--integrator",
        "implicit",
        "--sweeps",
        "3",
    ]);
    assert_eq!(lines[0]["integrator"], "implicit");
    assert_eq!(lines[0]["sweeps"], 3);
    let lines = run(&[
        "tower",
        "--dim",
        "2",
        "--bodies",
        "2",
        "--seconds",
        "0.1",
        "--model",
        "edge-repulsion",
    ]);
    assert_eq!(lines[0]["integrator"], "explicit");
    assert!(lines[0]["sweeps"].is_null());
}

#[test]
fn contact_scenes_measure_interpenetration_energy_and_cost() {
    for (scene, bodies) in [("stack", 2), ("squeeze", 3)] {
        let lines = run(&[
            scene,
            "--seconds",
            "0.2",
            "--model",
            "edge-repulsion",
            "rapier-volume",
        ]);
        assert_eq!(lines.len(), 4, "{scene}: two models, two dimensions");
        for l in &lines {
            assert_eq!(l["scene"], scene);
            assert_eq!(l["bodies"], bodies);
            assert!(l["max_interpenetration"].as_f64().unwrap() >= 0.0);
            assert!(l["energy_gain"].is_number() && l["rest_com"].is_number());
        }
    }
    let lines = run(&[
        "pile",
        "--dim",
        "3",
        "--bodies",
        "3",
        "5",
        "--seconds",
        "0.2",
        "--model",
        "edge-repulsion",
    ]);
    let counts: Vec<u64> = lines
        .iter()
        .map(|l| l["bodies"].as_u64().unwrap())
        .collect();
    assert_eq!(counts, [3, 5]);
    assert!(lines
        .iter()
        .all(|l| l["pairs_wall_s"].as_f64().unwrap() >= 0.0));
    let lines = run(&[
        "tower",
        "--bodies",
        "3",
        "--seconds",
        "0.2",
        "--model",
        "edge-repulsion",
        "rapier-volume",
    ]);
    assert_eq!(lines.len(), 4, "tower: two models, two dimensions");
    for l in &lines {
        assert_eq!(l["scene"], "tower");
        assert_eq!(l["bodies"], 3);
        let sinew = l["model"] == "edge-repulsion";
        assert_eq!(l["asleep"].is_boolean(), sinew, "{l:?}");
        assert!(l["scatter"].as_f64().unwrap() >= 0.0);
        assert!(l["top_height_ratio"].as_f64().unwrap() > 0.5);
        assert!(l["energy_over_start"].is_number() && l["energy_change"].is_number());
    }
    let lines = run(&[
        "pinch",
        "--dim",
        "2",
        "--mass",
        "0.5",
        "--model",
        "edge-repulsion",
        "rapier-volume",
    ]);
    assert_eq!(lines.len(), 2, "pinch: two models");
    for l in &lines {
        assert_eq!(l["scene"], "pinch");
        assert_eq!(l["mass"], 0.5);
        assert!(l["slip"].as_f64().unwrap() >= 0.0);
        assert!(l["overspeed"].as_f64().unwrap() >= 0.0);
        assert!(l["step_spike"].as_f64().unwrap() >= 1.0);
    }
    let lines = run(&[
        "roll",
        "--dim",
        "2",
        "--seconds",
        "0.3",
        "--model",
        "edge-repulsion",
        "rapier-volume",
    ]);
    assert_eq!(lines.len(), 2, "roll: two models");
    for l in &lines {
        assert_eq!(l["scene"], "roll");
        assert!((l["mass"].as_f64().unwrap() - 0.2).abs() < 1e-6);
        assert!(l["scatter"].as_f64().unwrap() >= 0.0);
        let sinew = l["model"] == "edge-repulsion";
        assert_eq!(l["max_penetration"].is_number(), sinew, "{l:?}");
        assert!(l["energy_over_start"].is_number() && l["energy_gain"].is_number());
    }
    let lines = run(&[
        "fold",
        "--dim",
        "2",
        "--seconds",
        "0.5",
        "--model",
        "edge-repulsion",
    ]);
    assert!(lines[0]["max_self_penetration"].is_number());
    let lines = run(&[
        "limb",
        "--dim",
        "2",
        "--seconds",
        "1",
        "--model",
        "edge-repulsion",
        "--self-contact",
        "on",
    ]);
    assert!(lines[0]["max_self_penetration"].is_number());
}

#[test]
fn bad_arguments_are_errors_not_panics() {
    let mut out = Vec::new();
    let e = cli::run(["scenes", "fall", "--model", "jelly"], &mut out).unwrap_err();
    assert!(e.contains("unknown model jelly"), "{e}");
    let e = cli::run(["scenes", "fall", "--iterations", "7"], &mut out).unwrap_err();
    assert!(e.contains("--iterations"), "{e}");
    let e = cli::run(["scenes", "explode"], &mut out).unwrap_err();
    assert!(e.contains("explode"), "{e}");
    assert!(out.is_empty());
}

#[test]
fn help_goes_to_stdout_and_succeeds_and_a_bad_flag_exits_2() {
    for argv in [&["scenes", "--help"][..], &["scenes", "fall", "--help"]] {
        let e = cli::parse(argv).unwrap_err();
        assert!(!e.use_stderr(), "{argv:?}");
        assert_eq!(e.exit_code(), 0, "{argv:?}");
        assert!(e.to_string().contains("Usage"), "{argv:?}");
    }
    let e = cli::parse(["scenes", "fall", "--bogus"]).unwrap_err();
    assert!(e.use_stderr());
    assert_eq!(e.exit_code(), 2);
}

#[test]
fn the_stretch_scene_measures_poisson_s_ratio() {
    let lines = run(&[
        "stretch",
        "--dim",
        "2",
        "--model",
        "edge-repulsion",
        "--poisson",
        "0.45",
        "--res",
        "3",
    ]);
    let nu = lines[0]["measured_poisson"].as_f64().unwrap();
    // A coarse bar (two cells across): the surface softens it, but it contracts far more than
    // the lattice's own 0.2.
    assert!(nu > 0.35 && nu < 0.5, "{nu}");
}

/// `scenes advise` as JSON lines: one per candidate, the record's keys plus `advise`.
fn advise(args: &[&str]) -> Vec<Value> {
    let mut argv = vec!["scenes", "advise", "--json"];
    argv.extend_from_slice(args);
    let mut out = Vec::new();
    let records = cli::run(argv.clone(), &mut out).unwrap_or_else(|e| panic!("{argv:?}: {e}"));
    let text = String::from_utf8(out).expect("utf-8 output");
    let lines: Vec<Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{l}: {e}")))
        .collect();
    assert_eq!(lines.len(), records.len(), "one line per candidate");
    lines
}

#[test]
fn advise_picks_the_cheapest_candidate_inside_the_bounds() {
    let lines = advise(&[
        "--dim", "2", "--trial", "crush", "--res", "3", "--mass", "10",
    ]);
    // Five models explicitly, four by each implicit integrator with 2 and with 10 sweeps, and
    // four under the default (Auto).
    assert_eq!(lines.len(), 25);
    let passing: Vec<&Value> = lines
        .iter()
        .filter(|l| l["advise"]["rejected"].is_null())
        .collect();
    for l in &lines {
        let a = &l["advise"];
        let (error, bound) = (a["error"].as_f64(), a["max_error"].as_f64().unwrap());
        let inside = !l["failed"].as_bool().unwrap()
            && l["min_vol_ratio"].as_f64().unwrap() >= a["min_volume_ratio"].as_f64().unwrap()
            && error.is_some_and(|e| e <= bound);
        assert_eq!(a["rejected"].is_null(), inside, "{l}");
    }
    let chosen: Vec<&Value> = lines
        .iter()
        .filter(|l| l["advise"]["chosen"] == true)
        .collect();
    assert_eq!(chosen.len(), 1, "10 kg on a 2D cube: some model passes");
    let cost = |l: &Value| l["wall_per_sim_s"].as_f64().unwrap();
    assert!(chosen[0]["advise"]["rejected"].is_null());
    assert!(passing.iter().all(|l| cost(chosen[0]) <= cost(l)));

    // No shape comes back exactly: with a zero error bound nothing passes, nothing is picked.
    let strict = advise(&[
        "--dim",
        "2",
        "--trial",
        "crush",
        "--res",
        "3",
        "--mass",
        "10",
        "--max-error",
        "0",
    ]);
    assert!(strict
        .iter()
        .all(|l| l["advise"]["chosen"] == false && l["advise"]["rejected"].as_str().is_some()));
}

#[test]
fn the_vibration_scene_measures_frequency_and_damping() {
    let lines = run(&["vibration", "--res", "2", "--model", "edge-repulsion"]);
    assert_eq!(lines.len(), 2, "both dimensions");
    for l in &lines {
        assert_eq!(l["scene"], "vibration");
        let (f, theory) = (
            l["measured_frequency"].as_f64().unwrap(),
            l["theory_frequency"].as_f64().unwrap(),
        );
        // √(E/ρ)/2L for the default bar: √10 / 2 Hz.
        assert!((theory - 10f64.sqrt() / 2.0).abs() < 1e-9);
        assert!((f / theory - 1.0).abs() < 0.1, "{f} against {theory}");
        assert!(l["measured_damping_ratio"].as_f64().unwrap() > 0.0);
    }
}

#[test]
fn the_bending_scene_measures_the_cantilevers_first_frequency() {
    let lines = run(&["bending", "--model", "springs"]);
    assert_eq!(lines.len(), 2, "both dimensions");
    for l in &lines {
        assert_eq!(l["scene"], "cantilever-ring");
        let (f, theory) = (
            l["measured_frequency"].as_f64().unwrap(),
            l["theory_frequency"].as_f64().unwrap(),
        );
        // Euler–Bernoulli for the default beam (1 m, 0.1 m thick, E = 10⁸ Pa, 1000 kg/m³):
        // 1.8751² √(E h² / 12 ρ) / 2π = 5.108 Hz.
        assert!((theory - 5.108).abs() < 1e-3, "theory {theory}");
        // Res 3 is stiff in bending (linear cells lock): 10–30 % high, not double.
        assert!((0.9..1.5).contains(&(f / theory)), "{f} against {theory}");
        assert!(l["sag"].as_f64().unwrap() > 0.0);
    }
}

#[test]
fn the_stretch_measures_youngs_modulus_from_the_pulled_ends_tension() {
    let lines = run(&["stretch", "--res", "5", "--model", "sinew", "rapier-volume"]);
    assert_eq!(lines.len(), 12, "six models, both dimensions");
    for l in &lines {
        let e = l["measured_young_modulus"].as_f64();
        if l["model"].as_str().unwrap().starts_with("rapier") {
            assert!(e.is_none(), "rapier's bodies expose no node forces: {l:?}");
        } else {
            // The default bar: E = 10⁴ Pa, pulled 2 %.
            let e = e.expect("sinew's models give the tension");
            assert!((e / 1.0e4 - 1.0).abs() < 0.05, "{}: E = {e}", l["model"]);
        }
    }
}
