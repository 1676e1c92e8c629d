//! Tests of `settings`.

use super::*;

#[test]
fn written_settings_load_back_identical() {
    let mut s = Settings::default();
    s.data.max_range = 60.0;
    s.runtime.scalar = Scalar::F32;
    s.capacities.map_points = Some(12345);
    let text = s.to_toml().unwrap();
    let back: Settings = toml::from_str(&text).unwrap();
    assert_eq!(back.voxel_size(), 0.6);
    assert_eq!(back.data, s.data);
    assert_eq!(back.runtime, s.runtime);
    // Written out, the capacities are explicit: the ones given and those sized from the
    // configuration, so the file says what the run used.
    assert_eq!(back.capacities.map_points, Some(12345));
    assert_eq!(back.capacities().unwrap(), s.capacities().unwrap());
    assert_eq!(back.capacities, s.capacities().unwrap().into());
    // An omitted kernel stays omitted, so the text loads back to the
    // same settings as the ones written: the Python bindings compare them.
    assert_eq!(back.registration, s.registration);
    assert_eq!(back.registration.kernel_scale, None);
}

#[test]
fn degeneracy_mode_is_read_and_reaches_the_core() {
    let s: Settings = toml::from_str("[registration]\ndegeneracy = \"robust\"\n").unwrap();
    assert_eq!(
        s.core_config::<f32>().unwrap().degeneracy,
        Degeneracy::Robust
    );
    let d = Settings::default().core_config::<f64>().unwrap();
    assert_eq!(d.degeneracy, Degeneracy::Reference);
    let err = toml::from_str::<Settings>("[registration]\ndegeneracy = \"on\"\n").unwrap_err();
    assert!(
        err.to_string().contains("expected `reference` or `robust`"),
        "{err}"
    );
}

#[test]
fn a_settings_file_naming_an_unknown_mode_is_refused_with_the_modes_there_are() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("old.toml");
    std::fs::write(&path, "[registration]\ndegeneracy = \"hold\"\n").unwrap();
    let err = format!("{:#}", Settings::load(&path).unwrap_err());
    println!("{err}");
    for said in ["old.toml", "`hold`", "expected `reference` or `robust`"] {
        assert!(err.contains(said), "{said:?} in {err}");
    }
}

#[test]
fn robust_mode_brings_its_defaults_and_keeps_what_is_given() {
    let robust = |text: &str| {
        let s: Settings =
            toml::from_str(&format!("[registration]\ndegeneracy = \"robust\"\n{text}")).unwrap();
        (s.core_config::<f64>().unwrap(), s.capacities().unwrap())
    };
    let (c, caps) = robust("");
    assert_eq!(c, Config::robust(100.0));
    assert_eq!(
        (c.voxel_size, c.kernel_scale, c.robust.plane_gate),
        (1.0, 1.0, 0.015)
    );
    assert_eq!(caps, Capacities::sized_for(&c, SCAN_POINTS));
    assert!(caps.plane_terms);
    let (c, caps) = robust(
        "kernel_scale = 0.5\nplane_gate = 1.0\n[mapping]\nvoxel_size = 0.7\n[capacities]\nmap_voxels = 5000\n",
    );
    assert_eq!(
        (c.voxel_size, c.kernel_scale, c.robust.plane_gate),
        (0.7, 0.5, 1.0)
    );
    assert_eq!(caps.map_voxels, 5000);
    assert!(
        caps.plane_terms,
        "robust mode needs room for its plane terms"
    );
    // What is not given is sized from the configuration (0.7 m voxels).
    assert_eq!(
        caps.map_points,
        Capacities::sized_for(&c, SCAN_POINTS).map_points
    );
    // Reference mode keeps kiss-icp's parameters, with capacities sized from them.
    let d = Settings::default();
    assert_eq!(d.core_config::<f64>().unwrap(), Config::new(100.0));
    let sized = Capacities::sized_for(&Config::<f64>::new(100.0), SCAN_POINTS);
    assert_eq!(d.capacities().unwrap(), sized);
    assert!(!sized.plane_terms);
    // Written out, the robust defaults are explicit and load back to the same.
    let s: Settings = toml::from_str("[registration]\ndegeneracy = \"robust\"\n").unwrap();
    let back: Settings = toml::from_str(&s.to_toml().unwrap()).unwrap();
    assert_eq!(
        back.core_config::<f64>().unwrap(),
        s.core_config::<f64>().unwrap()
    );
    assert_eq!(back.capacities().unwrap(), s.capacities().unwrap());
}

#[test]
fn a_written_default_kernel_is_no_change_from_the_reference() {
    let mut s = Settings::default();
    s.registration.kernel_scale = Some(1.0);
    assert!(s.changed_beyond_reference().is_empty());
    s.registration.kernel_scale = Some(0.5);
    assert_eq!(s.changed_beyond_reference(), ["registration.kernel_scale"]);
    let written: Settings = toml::from_str(&Settings::default().to_toml().unwrap()).unwrap();
    assert!(written.changed_beyond_reference().is_empty());
}

#[test]
fn unknown_keys_and_bad_values_are_refused() {
    assert!(toml::from_str::<Settings>("[data]\nmax_rnage = 3.0\n").is_err());
    let mut s = Settings::default();
    s.data.min_range = 200.0;
    assert!(s.core_config::<f64>().is_err());
}

#[test]
fn a_value_the_core_refuses_is_named_with_its_setting() {
    let msg = |edit: fn(&mut Settings)| {
        let mut s = Settings::default();
        edit(&mut s);
        format!("{:#}", s.validate().unwrap_err())
    };
    let m = msg(|s| s.registration.kernel_scale = Some(0.0));
    assert!(m.starts_with("registration.kernel_scale = 0.0: "), "{m}");
    let m = msg(|s| s.data.min_range = 200.0);
    assert!(m.starts_with("data.min_range = 200.0: "), "{m}");
    let m = msg(|s| s.capacities.map_voxels = Some(0));
    assert!(m.starts_with("capacities.map_voxels = 0: "), "{m}");
    let m = msg(|s| s.mapping.voxel_size = Some(-1.0));
    assert!(m.starts_with("mapping.voxel_size = -1.0: "), "{m}");
    Settings::default().validate().unwrap();
}

#[test]
fn non_finite_values_are_refused_by_name_and_printed_as_toml_writes_them() {
    let msg = |edit: fn(&mut Settings)| {
        let mut s = Settings::default();
        edit(&mut s);
        format!("{:#}", s.validate().unwrap_err())
    };
    let m = msg(|s| s.data.max_range = f64::NAN);
    assert_eq!(m, "data.max_range = nan: not a finite number");
    // inf would pass a `>= 1` check (plane_gate: every frame) and is still refused.
    let m = msg(|s| s.registration.plane_gate = f64::INFINITY);
    assert_eq!(m, "registration.plane_gate = inf: not a finite number");
    let m = msg(|s| s.mapping.voxel_size = Some(f64::NEG_INFINITY));
    assert!(m.starts_with("mapping.voxel_size = -inf"), "{m}");
    let text = "[adaptive_threshold]\nmin_motion_th = nan\n";
    let s: Settings = toml::from_str(text).unwrap();
    let m = format!("{:#}", s.validate().unwrap_err());
    assert_eq!(
        m,
        "adaptive_threshold.min_motion_th = nan: not a finite number"
    );
}

#[test]
fn kiss_icps_yaml_reads_as_its_python_package_reads_it() {
    // kiss-icp 1.3.0's own config/advanced.yaml layout.
    let yaml = "out_dir: results\n\
        data:\n  deskew: false\n  max_range: 60.0\n  min_range: 5.0\n\
        mapping:\n  voxel_size: null\n  max_points_per_voxel: 10\n\
        adaptive_threshold:\n  fixed_threshold: null\n  initial_threshold: 1.5\n  min_motion_th: 0.2\n\
        registration:\n  max_num_iterations: 300\n  convergence_criterion: 0.001\n  max_num_threads: 2\n";
    let s = Settings::from_kiss_icp_yaml(yaml).unwrap();
    let mut want = Settings {
        data: Data {
            max_range: 60.0,
            min_range: 5.0,
            deskew: false,
            redeskew: false,
        },
        adaptive_threshold: Threshold {
            initial_threshold: 1.5,
            min_motion_th: 0.2,
        },
        ..Settings::default()
    };
    want.mapping.voxel_size = Some(0.6); // kiss-icp's max_range / 100, made explicit
    want.mapping.max_points_per_voxel = 10;
    want.registration.max_num_iterations = 300;
    want.registration.convergence_criterion = 0.001;
    want.runtime.threads = 2;
    assert_eq!(s, want);
    // Empty is the defaults; ours sections are read too; runtime.threads wins.
    let d = Settings::from_kiss_icp_yaml("").unwrap();
    assert_eq!(d.voxel_size(), 1.0);
    assert_eq!(d.core_config::<f64>().unwrap(), Config::new(100.0));
    let both = "registration:\n  max_num_threads: 2\nruntime:\n  threads: 1\n  scalar: f32\n";
    let s = Settings::from_kiss_icp_yaml(both).unwrap();
    assert_eq!((s.runtime.threads, s.runtime.scalar), (1, Scalar::F32));
    // What the Python package refuses, this refuses, naming it.
    for (bad, named) in [
        (
            "adaptive_threshold:\n  fixed_threshold: 0.3\n",
            "fixed_threshold = 0.3",
        ),
        ("data:\n  max_rnage: 3.0\n", "max_rnage"),
        ("dataa:\n  max_range: 3.0\n", "unknown section `dataa`"),
        ("data:\n  max_range: [1]\n", "`data`"),
    ] {
        let e = format!("{:#}", Settings::from_kiss_icp_yaml(bad).unwrap_err());
        assert!(e.contains(named), "{bad}: {e}");
    }
}

#[test]
fn threads_are_capped_to_the_cores_with_a_warning() {
    let mut s = Settings::default();
    let cores = cores();
    assert_eq!((s.threads(), s.threads_warning()), (cores, None));
    s.runtime.threads = usize::MAX;
    assert_eq!(s.threads(), cores);
    let w = s.threads_warning().unwrap();
    assert!(w.contains(&usize::MAX.to_string()), "{w}");
    s.runtime.threads = 1;
    assert_eq!((s.threads(), s.threads_warning()), (1, None));
}

#[test]
fn the_accurate_preset_gives_its_defaults_and_what_is_given_wins() {
    let dir = tempfile::tempdir().unwrap();
    let file = |name: &str, text: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    // No file: the preset's configuration, its voxels following the range.
    let a = Settings::preset(PresetName::Accurate);
    assert_eq!(a.core_config::<f64>().unwrap(), Config::accurate(100.0));
    assert!(a.capacities().unwrap().plane_terms);
    let default = Settings::preset(PresetName::Default);
    assert_eq!(default, Settings::default());
    // From a file: what it gives wins, the rest is the preset's.
    let p = file(
        "a.toml",
        "[pipeline]\npreset = \"accurate\"\n[data]\nmax_range = 60.0\n[registration]\nmax_num_iterations = 70\n",
    );
    let s = Settings::load(&p).unwrap();
    let want = Config {
        max_iterations: 70,
        ..Config::accurate(60.0)
    };
    assert_eq!(s.core_config::<f64>().unwrap(), want);
    // The flag replaces the file's preset; the file's values still win.
    let d = Settings::load_as(&p, Some(PresetName::Default)).unwrap();
    assert_eq!(d.voxel_size(), 0.6);
    assert_eq!(d.registration.degeneracy, DegeneracyMode::Reference);
    assert_eq!(d.registration.max_num_iterations, 70);
    // A plain file over the accurate preset.
    let plain = file("b.toml", "[data]\nmax_range = 80.0\n");
    let s = Settings::load_as(&plain, Some(PresetName::Accurate)).unwrap();
    assert_eq!(s.core_config::<f64>().unwrap(), Config::accurate(80.0));
    // config.toml as `run` writes it loads back to the same settings.
    let written = file("c.toml", &s.to_toml().unwrap());
    assert_eq!(
        Settings::load(&written)
            .unwrap()
            .core_config::<f64>()
            .unwrap(),
        Config::accurate(80.0)
    );
    // kiss-icp's YAML over the preset: its keys win, the preset gives the rest.
    let yaml = file(
        "k.yaml",
        "data:\n  max_range: 50.0\nmapping:\n  max_points_per_voxel: 12\n",
    );
    let s = Settings::load_as(&yaml, Some(PresetName::Accurate)).unwrap();
    let want = Config {
        max_points_per_voxel: 12,
        ..Config::accurate(50.0)
    };
    assert_eq!(s.core_config::<f64>().unwrap(), want);
    // Unknown keys are still refused, with the file named.
    let bad = file("d.toml", "[pipeline]\npreset = \"accurate\"\nvoxel = 1\n");
    let e = format!("{:#}", Settings::load(&bad).unwrap_err());
    assert!(e.contains("d.toml") && e.contains("voxel"), "{e}");
    let bad = file("e.toml", "[pipeline]\npreset = \"fastest\"\n");
    assert!(Settings::load(&bad).is_err());
}

#[test]
fn robust_settings_in_reference_mode_are_said_unused_and_in_robust_mode_not() {
    let mut s = Settings::default();
    assert!(s.unused_warnings().is_empty());
    s.registration.lateral_prior = 1.0;
    s.registration.cycle_stop = !s.registration.cycle_stop;
    let w = s.unused_warnings();
    assert_eq!(w.len(), 2, "{w:?}");
    assert!(
        w[0].contains("registration.lateral_prior = 1.0 not used"),
        "{w:?}"
    );
    assert!(
        w[1].contains("cycle_stop") && w[1].contains("robust mode only"),
        "{w:?}"
    );
    // Every robust-only setting is named when set.
    let mut all = Settings::default();
    let r = &mut all.registration;
    (r.plane_gate, r.prediction_prior, r.lateral_prior) = (0.5, 0.5, 0.5);
    r.plane_kernel_scale = 0.5;
    r.cycle_stop = !r.cycle_stop;
    assert_eq!(all.unused_warnings().len(), 5);
    // Robust mode uses them: nothing to say.
    s.registration.degeneracy = DegeneracyMode::Robust;
    assert!(s.unused_warnings().is_empty());
}
