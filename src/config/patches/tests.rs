use crate::config::Config;
use splinewatch_core::response::frf::{Sensor, SensorPoint};

const DECK: &str = include_str!("../../../tests/fixtures/slab_on_webs.toml");

/// A patch away from the deck: joined to nothing, supported by nothing.
const FLOATING: &str = r#"
[[model.patches]]
name = "floating"
material = "concrete"
thickness = 0.2
degree = [2, 2]
control_points = [3, 3]
[model.patches.geometry]
kind = "rectangular_plate"
length = 2.0
width = 2.0
origin = [30.0, 0.0, 0.0]
"#;

fn message(text: &str) -> String {
    match Config::from_toml(text).and_then(|c| c.validate()) {
        Ok(()) => panic!("accepted: {}", &text[text.len().saturating_sub(200)..]),
        Err(e) => e.to_string(),
    }
}

#[test]
fn a_deck_of_patches_becomes_a_model_with_joints_bearings_and_sensors() {
    let config = Config::from_toml(DECK).unwrap();
    config.validate().unwrap();
    let model = config.build_model().unwrap();
    assert_eq!(model.patches.len(), 3);
    assert_eq!(model.joints.len(), 2);
    assert_eq!(model.bearings.len(), 4);
    // The bearings sit under the webs' bottom edges (η = 1), at the ends.
    let first = model.bearings[0].at();
    assert_eq!((first.patch, first.xi, first.eta, first.tau), (1, 0.0, 1.0, 0.0));
    let sensors: Vec<SensorPoint> = config
        .build_sensors(&model)
        .unwrap()
        .into_iter()
        .map(|(_, s)| match s {
            Sensor::Shell(p) => p,
            Sensor::Beam(_) => panic!("no beam in this config"),
        })
        .collect();
    assert_eq!((sensors[0].patch, sensors[1].patch), (0, 2));
    assert!((sensors[0].xi - 0.5).abs() < 1e-9 && (sensors[0].eta - 1.0 / 6.0).abs() < 1e-9);
    let names: Vec<String> = config.build_parameters().unwrap().into_iter().map(|p| p.name).collect();
    assert_eq!(names[..3], ["west_south.kx", "west_south.ky", "west_south.kz"]);
    // κ: no spring fields, then the four bearings.
    assert_eq!(model.spring_coefficients().len(), 4);
    let modes = model.assemble().unwrap().modes().unwrap();
    let f = modes.frequencies_hz();
    assert!(f[0] > 1.0 && f[0] < 30.0, "{f:?}");
}

#[test]
fn a_cad_surface_is_refined_to_the_analysis_net_unchanged() {
    // The south web as a bilinear CAD patch (degree 1), analysed at
    // degree 1 on a 12 × 3 net; a web of the same geometry.
    let cad = DECK.replacen(
        "degree = [3, 2]\ncontrol_points = [12, 3]\n[model.patches.geometry]\nkind = \"quadrilateral\"\ncorners = [[0.0, -2.0, 0.0], [20.0, -2.0, 0.0], [20.0, -2.0, -1.5], [0.0, -2.0, -1.5]]",
        "degree = [1, 1]\ncontrol_points = [12, 3]\n[model.patches.geometry]\nkind = \"nurbs\"\ndegree_xi = 1\ndegree_eta = 1\nknots_xi = [0.0, 0.0, 1.0, 1.0]\nknots_eta = [0.0, 0.0, 1.0, 1.0]\ncontrol_points = [[0.0, -2.0, 0.0], [0.0, -2.0, -1.5, 1.0], [20.0, -2.0, 0.0], [20.0, -2.0, -1.5]]",
        1,
    );
    assert_ne!(cad, DECK);
    let model = Config::from_toml(&cad).unwrap().build_model().unwrap();
    let web = model.patches[1].shell.surface();
    assert_eq!(web.net_size(), (12, 3));
    let r = web.evaluate(0.3, 0.6).r;
    assert!(
        (r[0] - 6.0).abs() < 1e-12 && (r[1] + 2.0).abs() < 1e-12 && (r[2] + 0.9).abs() < 1e-12,
        "{r:?}"
    );
    assert_eq!(model.joints.len(), 2);
    // A weight of 2 at the (ξ=0, η=1) corner: a rational surface, refined
    // exactly (homogeneous coordinates). At (½, ½) all four bilinear
    // products are ¼, W = ¼ (1 + 2 + 1 + 1) = 1.25, so
    // r = ¼ (P00 + 2 P01 + P10 + P11) / 1.25 = (8, −2, −0.9).
    let rational = cad.replace("[0.0, -2.0, -1.5, 1.0]", "[0.0, -2.0, -1.5, 2.0]");
    let model = Config::from_toml(&rational).unwrap().build_model().unwrap();
    let web = model.patches[1].shell.surface();
    assert_eq!(web.net_size(), (12, 3));
    assert!(web.weights().is_some());
    let r = web.evaluate(0.5, 0.5).r;
    assert!(
        (r[0] - 8.0).abs() < 1e-12 && (r[1] + 2.0).abs() < 1e-12 && (r[2] + 0.9).abs() < 1e-12,
        "{r:?}"
    );
    assert_eq!(model.joints.len(), 2);
    let zero = cad.replace("[0.0, -2.0, -1.5, 1.0]", "[0.0, -2.0, -1.5, 0.0]");
    let e = Config::from_toml(&zero)
        .and_then(|c| c.validate())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("model.patches[1].geometry.control_points") && e.contains("weight 0 must be finite and positive"),
        "{e}"
    );
}

#[test]
fn a_web_tapers_by_a_thickness_field() {
    // The south web 0.25 m at the slab, 0.35 m at its bottom edge.
    let tapered = DECK.replacen(
        "thickness = 0.25",
        "thickness = { knots_xi = [0.0, 1.0], degree_xi = 0, knots_eta = [0.0, 0.0, 1.0, 1.0], degree_eta = 1, values = [0.25, 0.35] }",
        1,
    );
    let model = Config::from_toml(&tapered).unwrap().build_model().unwrap();
    let web = &model.patches[1].shell;
    let (m, n) = web.surface().net_size();
    let t = web.thickness();
    assert!((t[0] - 0.25).abs() < 1e-12 && (t[n - 1] - 0.35).abs() < 1e-12 && (t[(m - 1) * n + 1] - 0.3).abs() < 1e-12);
    let wrong = tapered.replace("values = [0.25, 0.35]", "values = [0.25]");
    let e = Config::from_toml(&wrong)
        .and_then(|c| c.validate())
        .unwrap_err()
        .to_string();
    assert!(e.contains("model.patches[1].thickness.values"), "{e}");
}

#[test]
fn bad_decks_name_their_key() {
    let cases = [
        (
            DECK.replacen("material = \"concrete\"", "material = \"steel\"", 1),
            "model.patches[0].material",
        ),
        (
            DECK.replacen("name = \"web_north\"", "name = \"slab\"", 1),
            "model.patches[2].name",
        ),
        (format!("{DECK}\n{FLOATING}"), "model.patches[3]"),
        (
            format!(
                "{DECK}\n{}",
                FLOATING.replace("origin = [30.0, 0.0, 0.0]", "origin = [5.0, -1.0, 0.0]")
            ),
            "lies on patch",
        ),
        (
            DECK.replacen("at = [0.0, -2.0, -1.5]", "at = [0.0, -2.0, -4.0]", 1),
            "model.bearings[0].at",
        ),
        (
            DECK.replacen("x = 10.0\ny = -2.0\nz = 0.1", "x = 10.0\ny = -2.0", 1),
            "sensors[0].z",
        ),
        (
            DECK.replacen("patch = \"web_north\"", "patch = \"web_west\"", 1),
            "sensors[1].patch",
        ),
        (
            format!("{DECK}\n[[model.constraints]]\nedge = \"xi0\"\nkind = \"clamped\"\n"),
            "model.constraints[0].patch",
        ),
        (
            format!(
                "{DECK}\n[model.geometry]\nkind = \"rectangular_plate\"\nlength = 1.0\nwidth = 1.0\nthickness = 0.1\n"
            ),
            "model.patches",
        ),
    ];
    for (text, key) in cases {
        let e = message(&text);
        assert!(e.contains(key), "{key}: {e}");
    }
}

/// A bearing on a skewed support line: `axes` turns its `kx, ky, kz`
/// (the model's bearing keeps them); axes that are not orthonormal and
/// right-handed are refused by key.
#[test]
fn a_bearing_takes_the_axes_of_its_support_line() {
    let skew = "stiffness = [1e8, 1e8, 2e9]\nbounds = [1e6, 1e10]\naxes = [[0.7782431485260211, 0.6279630576493378, 0.0], [-0.6279630576493378, 0.7782431485260211, 0.0], [0.0, 0.0, 1.0]]\n";
    let text = DECK.replacen("stiffness = [1e8, 1e8, 2e9]\nbounds = [1e6, 1e10]\n", skew, 1);
    assert_ne!(text, DECK);
    let config = Config::from_toml(&text).unwrap();
    let model = config.build_model().unwrap();
    assert_eq!(
        model.bearings[0].axes()[1],
        [-0.6279630576493378, 0.7782431485260211, 0.0]
    );
    assert_eq!(model.bearings[1].axes()[1], [0.0, 1.0, 0.0]);
    let left_handed = text.replacen("[0.0, 0.0, 1.0]]", "[0.0, 0.0, -1.0]]", 1);
    assert!(
        message(&left_handed).contains("model.bearings[0].axes"),
        "{}",
        message(&left_handed)
    );
    // `skew_deg = 38.9` gives the same axes (to round-off).
    let by_angle = DECK.replacen(
        "stiffness = [1e8, 1e8, 2e9]\nbounds = [1e6, 1e10]\n",
        "stiffness = [1e8, 1e8, 2e9]\nbounds = [1e6, 1e10]\nskew_deg = 38.9\n",
        1,
    );
    let turned = Config::from_toml(&by_angle).unwrap().build_model().unwrap();
    for (a, b) in turned.bearings[0]
        .axes()
        .iter()
        .flatten()
        .zip(model.bearings[0].axes().iter().flatten())
    {
        assert!((a - b).abs() < 1e-15, "{a} vs {b}");
    }
    for (text, why) in [
        (
            by_angle.replacen("skew_deg = 38.9", "skew_deg = 90.0", 1),
            "strictly between",
        ),
        (text.replacen("axes = ", "skew_deg = 10.0\naxes = ", 1), "not both"),
    ] {
        let e = message(&text);
        assert!(e.contains("model.bearings[0].skew_deg") && e.contains(why), "{e}");
    }
}

/// The guide's multi-patch monitoring example stays a valid config:
/// a modulus field on each patch, the bearing updated, `[monitoring]`.
#[test]
fn the_monitoring_example_of_several_patches_builds() {
    let config = Config::from_toml(include_str!("../../../tests/fixtures/slab_on_webs_monitoring.toml")).unwrap();
    let model = config.build_model().unwrap();
    let fields: Vec<usize> = model.stiffness_fields.iter().map(|f| f.patch()).collect();
    assert_eq!(fields, [0, 1, 2]);
    assert_eq!(config.monitoring.as_ref().map(|m| m.training_windows), Some(100));
}
