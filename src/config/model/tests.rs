//! `[[model.stiffness_fields]]` read and built.

use super::*;
use splinewatch_core::updating::ParameterKind;

fn with_field(section: &str) -> Result<Config, ConfigError> {
    let text = format!("{}\n{section}", include_str!("../../../config/sinello.toml"));
    let config = Config::from_toml(&text)?;
    config.build_model()?;
    Ok(config)
}

const REGIONS: &str = r#"
[[model.stiffness_fields]]
name = "deck"
knots_xi = [0.0, 0.25, 0.5, 0.75, 1.0]
degree_xi = 0
knots_eta = [0.0, 0.5, 1.0]
degree_eta = 0
bounds = [0.3, 1.5]
"#;

#[test]
fn a_field_becomes_model_coefficients_and_parameters() {
    let config = with_field(REGIONS).unwrap();
    let model = config.build_model().unwrap();
    assert_eq!(model.stiffness_fields.len(), 1);
    assert_eq!(model.stiffness_fields[0].coefficients(), &[1.0; 8]);
    let names: Vec<String> = config.build_parameters().unwrap().into_iter().map(|p| p.name).collect();
    let fields: Vec<&String> = names.iter().filter(|n| n.starts_with("deck.s")).collect();
    assert_eq!(fields.len(), 8);
    assert_eq!(fields[0], "deck.s1");
    assert_eq!(fields[7], "deck.s8");
    // Not updated: no parameters, the coefficients still set the model.
    let fixed = with_field(&REGIONS.replace(
        "bounds = [0.3, 1.5]",
        "update = false\ncoefficients = [1, 1, 1, 1, 1, 0.7, 1, 1]",
    ))
    .unwrap();
    assert!(!fixed
        .build_parameters()
        .unwrap()
        .iter()
        .any(|p| p.name.starts_with("deck.")));
    assert_eq!(fixed.build_model().unwrap().stiffness_fields[0].coefficients()[5], 0.7);
}

#[test]
fn bad_fields_name_their_key() {
    let message = |section: String| with_field(&section).unwrap_err().to_string();
    assert!(message(REGIONS.replace("name = \"deck\"", "name = \"east\"")).contains("model.stiffness_fields[0].name"));
    assert!(message(REGIONS.replace("bounds", "scales = \"E1\"\nbounds")).contains("model.stiffness_fields[0].scales"));
    let bending = with_field(&REGIONS.replace("bounds", "scales = \"bending\"\nbounds")).unwrap();
    assert_eq!(
        bending.build_model().unwrap().stiffness_fields[0].scale(),
        StiffnessScale::Bending
    );
    assert!(
        message(REGIONS.replace("bounds = [0.3, 1.5]", "coefficients = [1.0, 2.0]"))
            .contains("model.stiffness_fields[0].coefficients")
    );
    assert!(message(REGIONS.replace("[0.3, 1.5]", "[0.0, 1.5]")).contains("model.stiffness_fields[0].bounds"));
    assert!(
        message(REGIONS.replace("[0.0, 0.5, 1.0]", "[0.0, 0.5, 1.2]")).contains("model.stiffness_fields[0].knots_eta")
    );
    let no_bounds = Config::from_toml(&format!(
        "{}\n{}",
        include_str!("../../../config/sinello.toml"),
        REGIONS.replace("bounds = [0.3, 1.5]", "")
    ))
    .unwrap();
    assert!(no_bounds
        .build_parameters()
        .unwrap_err()
        .to_string()
        .contains("model.stiffness_fields[0].bounds"));
}

/// The guide's deck on a bent: beams, a rigid cap and the columns' bases
/// on their own ground; its modes those of the core's check against
/// OpenSees (the same structure and nets there: 0.61 %).
#[test]
fn a_deck_on_a_bent_builds_from_its_config() {
    let config = Config::from_toml(include_str!("../../../config/examples/deck-on-bent.toml")).unwrap();
    let model = config.build_model().unwrap();
    assert_eq!(model.beams.members().len(), 2);
    assert_eq!(model.beams.node_count(), 18);
    assert_eq!(model.rigid_bodies.len(), 1);
    let groups = config.support_groups(&model).unwrap();
    assert_eq!(groups.names(), ["west", "east", "bent"]);
    assert_eq!((groups.of_beam_base(0), groups.of_beam_base(1)), (2, 2));
    let modes = model.assemble().unwrap().modes().unwrap();
    let opensees = [1.0027, 1.7953, 2.4695, 2.9603, 3.9738];
    for (ours, theirs) in modes.frequencies_hz().iter().zip(opensees) {
        assert!(
            (ours / theirs - 1.0).abs() < 1e-2,
            "{ours} Hz against OpenSees's {theirs}"
        );
    }
}

#[test]
fn bad_beams_and_rigid_bodies_name_their_key() {
    let text = include_str!("../../../config/examples/deck-on-bent.toml");
    let message = |from: &str, to: &str| {
        assert!(text.contains(from), "{from}");
        let config = Config::from_toml(&text.replacen(from, to, 1));
        match config {
            Err(e) => e.to_string(),
            Ok(c) => c.build_model().unwrap_err().to_string(),
        }
    };
    let zero = message("end = [20.0, 2.0, -0.5]", "end = [20.0, 2.0, -7.0]");
    assert!(
        zero.contains("model.beams[0].end") && zero.contains("zero length"),
        "{zero}"
    );
    let empty = message(
        "edges = [{ patch = \"span1\", edge = \"xi1\" }, { patch = \"span2\", edge = \"xi0\" }]\nbeam_ends = [\"bent.south:end\", \"bent.north:end\"]",
        "",
    );
    assert!(
        empty.contains("model.rigid[0].edges") && empty.contains("holds nothing"),
        "{empty}"
    );
    let held = message(
        "edge = \"xi1\" }, { patch = \"span2\"",
        "edge = \"xi0\" }, { patch = \"span2\"",
    );
    assert!(
        held.contains("model.rigid[0]") && held.contains("already held"),
        "{held}"
    );
    let unknown = message("\"bent.north:end\"]", "\"bent.west:end\"]");
    assert!(
        unknown.contains("model.rigid[0].beam_ends[1]") && unknown.contains("not a beam"),
        "{unknown}"
    );
    let orthotropic = message(
        "young = 3.0e10\npoisson = 0.2",
        "e1 = 3e10\ne2 = 3e10\ng12 = 1.25e10\ng13 = 1.25e10\ng23 = 1.25e10\nnu12 = 0.2",
    );
    assert!(
        orthotropic.contains("a beam needs an isotropic material"),
        "{orthotropic}"
    );
    let both = message("poisson = 0.2", "poisson = 0.2\ne1 = 3e10");
    assert!(
        both.contains("model.materials.concrete") && both.contains("not both"),
        "{both}"
    );
    let base = message("base = \"fixed\"", "base = \"west\"");
    assert!(base.contains("model.beams[0].base"), "{base}");
    let section = message("section = { circle = 1.2 }", "section = { circle = 1.2, area = 1.0 }");
    assert!(section.contains("model.beams[0].section"), "{section}");
}

const WEST_ABUTMENT: &str = r#"
[[model.supports]]
name = "west_abutment"
edge = { patch = "span1", edge = "xi0" }
support = "west"
stiffness = { y = 2e8, ry = 5e8 }
bounds = [1e5, 1e12]
update = ["ry"]
"#;

/// A line support on the west abutment: its components in κ after the
/// bearings, its updated one a parameter, its ground the abutment's; its
/// rotational restraint stiffens the first vertical modes.
#[test]
fn a_line_support_builds_with_its_parameters_and_ground() {
    let base = include_str!("../../../config/examples/deck-on-bent.toml");
    let config = Config::from_toml(&format!("{base}\n{WEST_ABUTMENT}")).unwrap();
    let model = config.build_model().unwrap();
    assert_eq!(model.elastic_supports.len(), 1);
    assert_eq!(model.spring_coefficients(), vec![vec![2e8, 5e8]]);
    let names: Vec<String> = config.build_parameters().unwrap().into_iter().map(|p| p.name).collect();
    assert_eq!(names, ["west_abutment.ry"]);
    assert_eq!(
        config.parameter_family(&names[0]),
        Some(crate::config::ParameterFamily::ElasticSupport)
    );
    let groups = config.support_groups(&model).unwrap();
    assert_eq!(groups.names()[groups.of_spring(0)], "west");
    let bare = Config::from_toml(base).unwrap().build_model().unwrap();
    let (with, without) = (
        model.assemble().unwrap().modes().unwrap().frequencies_hz(),
        bare.assemble().unwrap().modes().unwrap().frequencies_hz(),
    );
    assert!(with.iter().zip(&without).take(6).all(|(a, b)| a >= b));
    assert!(with.iter().zip(&without).take(6).any(|(a, b)| a > &(b * 1.01)));
}

#[test]
fn bad_line_supports_name_their_key() {
    let base = include_str!("../../../config/examples/deck-on-bent.toml");
    let message = |from: &str, to: &str| {
        let text = format!("{base}\n{}", WEST_ABUTMENT.replacen(from, to, 1));
        let config = Config::from_toml(&text).unwrap();
        config
            .build_model()
            .and_then(|_| config.build_parameters())
            .unwrap_err()
            .to_string()
    };
    let negative = message("ry = 5e8", "ry = -5e8");
    assert!(
        negative.contains("model.supports[0].stiffness") && negative.contains("ry"),
        "{negative}"
    );
    let absent = message("update = [\"ry\"]", "update = [\"rx\"]");
    assert!(absent.contains("model.supports[0].update"), "{absent}");
    let unbounded = message("bounds = [1e5, 1e12]\n", "");
    assert!(unbounded.contains("model.supports[0].bounds"), "{unbounded}");
    let missing = message("patch = \"span1\"", "patch = \"span9\"");
    assert!(missing.contains("model.supports[0].edge.patch"), "{missing}");
    let skew = message(
        "support = \"west\"",
        "support = \"west\"\naxes = [[1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 1.0]]",
    );
    assert!(skew.contains("model.supports[0].axes"), "{skew}");
    let both = message(
        "support = \"west\"",
        "support = \"west\"\nskew_deg = 20.0\naxes = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]",
    );
    assert!(both.contains("model.supports[0].skew_deg"), "{both}");
}

const POT_BEARINGS: &str = r#"
[[model.supports]]
name = "pot.west"
at = [10.0, 4.0, -0.2]
support = "west"
stiffness = { z = 2e9, rx = 1e9, ry = 1e9 }
bounds = [1e6, 1e12]
update = ["ry"]

[[model.supports]]
name = "pot.east"
at = [30.0, 4.0, -0.2]
support = "west"
stiffness = { z = 2e9, rx = 1e9, ry = 1e9 }
update = ["ry"]
tie = "pot.west"
"#;

/// Two point supports under the spans' middles (on the soffit, as a
/// bearing's), tied: one parameter `pot.west.ry` in N m/rad; they stiffen
/// the first vertical modes. A point support given with an `edge` too, or a `patch`
/// without `at`, is refused by key.
#[test]
fn point_supports_build_tied_with_their_units() {
    use splinewatch_core::model::elastic_supports::SupportSite;
    let base = include_str!("../../../config/examples/deck-on-bent.toml");
    let config = Config::from_toml(&format!("{base}\n{POT_BEARINGS}")).unwrap();
    let model = config.build_model().unwrap();
    assert_eq!(model.elastic_supports.len(), 2);
    let SupportSite::Point(at) = model.elastic_supports[1].site() else {
        panic!("{:?}", model.elastic_supports[1].site())
    };
    let shell = &model.patches[at.patch].shell;
    let position = shell.position(at.xi, at.eta, at.tau);
    assert_eq!((model.patches[at.patch].name(), at.tau), ("span2", 0.0));
    assert!(
        (position[0] - 30.0).abs() < 1e-9 && (position[2] + 0.2).abs() < 1e-9,
        "{position:?}"
    );
    let names: Vec<String> = config.build_parameters().unwrap().into_iter().map(|p| p.name).collect();
    assert_eq!(names, ["pot.west.ry"]);
    assert_eq!(config.parameter_unit("pot.west.ry"), "Nm/rad");
    let bare = Config::from_toml(base).unwrap().build_model().unwrap();
    let (with, without) = (
        model.assemble().unwrap().modes().unwrap().frequencies_hz(),
        bare.assemble().unwrap().modes().unwrap().frequencies_hz(),
    );
    // Springs only raise the sorted frequencies (Weyl); modes with a node
    // at both points keep theirs to round-off.
    assert!(
        with.iter().zip(&without).take(6).all(|(a, b)| *a >= b * (1.0 - 1e-9)),
        "{with:?} vs {without:?}"
    );
    assert!(
        with.iter().zip(&without).take(6).any(|(a, b)| *a > b * 1.01),
        "{with:?} vs {without:?}"
    );
    let message = |from: &str, to: &str| {
        let config = Config::from_toml(&format!("{base}\n{}", POT_BEARINGS.replacen(from, to, 1))).unwrap();
        config.build_model().unwrap_err().to_string()
    };
    let both = message(
        "support = \"west\"",
        "support = \"west\"\nedge = { patch = \"span1\", edge = \"xi0\" }",
    );
    assert!(
        both.contains("model.supports[0].at") && both.contains("not both"),
        "{both}"
    );
    let stray = message("at = [10.0, 4.0, -0.2]", "patch = \"span1\"");
    assert!(stray.contains("model.supports[0].patch"), "{stray}");
    let far = message("at = [10.0, 4.0, -0.2]", "at = [10.0, 4.0, -3.0]");
    assert!(far.contains("model.supports[0].at"), "{far}");
}

const FOOTINGS: &str = r#"
[[model.supports]]
name = "footings"
support = "bent"
stiffness = { x = 2e9, y = 2e9, z = 5e8, rx = 1e10, ry = 1e10, rz = 1e10 }
bounds = [1e6, 1e13]
update = ["z", "ry"]
"#;

/// The columns' bases on a support without an edge (their footings): the
/// support acts at both bases with one parameter per updated component,
/// its ground the bent's, the bases free in the members (the springs hold
/// them); softer footings lower the first modes; the parameters' units are
/// N/m and N m/rad (not per metre).
#[test]
fn beam_bases_stand_on_a_support_without_an_edge() {
    let base = include_str!("../../../config/examples/deck-on-bent.toml");
    let on_footings = base.replace("base = \"fixed\"\nsupport = \"bent\"", "base = \"footings\"");
    let config = Config::from_toml(&format!("{on_footings}\n{FOOTINGS}")).unwrap();
    let model = config.build_model().unwrap();
    assert_eq!(model.elastic_supports.len(), 1);
    let nodes = match model.elastic_supports[0].site() {
        splinewatch_core::model::elastic_supports::SupportSite::BeamNodes(nodes) => nodes.clone(),
        other => panic!("{other:?}"),
    };
    assert_eq!(nodes, [model.beams.member_nodes(0)[0], model.beams.member_nodes(1)[0]]);
    assert!(model.beams.base_nodes().is_empty(), "no base is held");
    let names: Vec<String> = config.build_parameters().unwrap().into_iter().map(|p| p.name).collect();
    assert_eq!(names, ["footings.z", "footings.ry"]);
    assert_eq!(config.parameter_unit("footings.z"), "N/m");
    assert_eq!(config.parameter_unit("footings.ry"), "Nm/rad");
    let groups = config.support_groups(&model).unwrap();
    assert_eq!(groups.names()[groups.of_spring(0)], "bent");
    let fixed = Config::from_toml(base).unwrap().build_model().unwrap();
    let (soft, stiff) = (
        model.assemble().unwrap().modes().unwrap().frequencies_hz(),
        fixed.assemble().unwrap().modes().unwrap().frequencies_hz(),
    );
    assert!(
        soft.iter().zip(&stiff).take(6).all(|(a, b)| a <= &(b * (1.0 + 1e-9))),
        "{soft:?} {stiff:?}"
    );
    assert!(
        soft.iter().zip(&stiff).take(6).any(|(a, b)| a < &(b * 0.99)),
        "{soft:?} {stiff:?}"
    );
}

#[test]
fn bad_footings_name_their_key() {
    let base = include_str!("../../../config/examples/deck-on-bent.toml");
    let message = |text: String| Config::from_toml(&text).unwrap().build_model().unwrap_err().to_string();
    let on_footings = base.replacen("base = \"fixed\"\nsupport = \"bent\"", "base = \"footings\"", 1);
    // A support without an edge that no base names.
    let alone = message(format!("{base}\n{FOOTINGS}"));
    assert!(
        alone.contains("model.supports[0].edge") && alone.contains("no beam's `base` names it"),
        "{alone}"
    );
    // A base on a support along an edge.
    let on_edge = message(format!(
        "{}\n{WEST_ABUTMENT}",
        base.replacen("base = \"fixed\"", "base = \"west_abutment\"", 1)
    ));
    assert!(
        on_edge.contains("model.beams[0].base") && on_edge.contains("a support on a patch"),
        "{on_edge}"
    );
    // A base on a support and a ground of its own.
    let twice = message(format!(
        "{}\n{FOOTINGS}",
        base.replacen(
            "base = \"fixed\"\nsupport = \"bent\"",
            "base = \"footings\"\nsupport = \"west\"",
            1
        )
    ));
    assert!(twice.contains("model.beams[0].support"), "{twice}");
    let unknown = message(on_footings.clone());
    assert!(
        unknown.contains("model.beams[0].base") && unknown.contains("\"footings\""),
        "{unknown}"
    );
}

/// A ground channel pointing along −x (a station's "Long" channels on the
/// Painter Street bridge) enters its ground input with the opposite sign;
/// its axis and group are those of "x"; a deck channel may point along −x
/// too. The groups hold the model where their supports are: the bent's
/// ground at its columns' footings, each abutment's along its line support.
#[test]
fn a_channel_pointing_the_other_way_enters_with_the_opposite_sign() {
    let text = include_str!("../../../config/painter-street-bridge.toml");
    let config = Config::from_toml(text).unwrap();
    let model = config.build_model().unwrap();
    let groups = config.support_groups(&model).unwrap();
    let plan = config.ground_plan(&groups).unwrap();
    let index = |name: &str| config.sensors.iter().position(|s| s.name == name).unwrap();
    let bent_x = plan.iter().find(|p| p.name == "bent.x").unwrap();
    assert_eq!(
        (bent_x.sensors.clone(), bent_x.inverted.clone()),
        (vec![index("ch1")], vec![index("ch1")])
    );
    assert!(plan.iter().find(|p| p.name == "bent.y").unwrap().inverted.is_empty());
    assert_eq!(bent_x.describe(&config), "bent.x ← −ch1");
    let samples: Vec<Vec<f64>> = (0..config.sensors.len()).map(|i| vec![i as f64 + 1.0; 3]).collect();
    let signals = crate::config::ground_signals(&plan, |i| &samples[i]);
    let at = |name: &str| plan.iter().position(|p| p.name == name).unwrap();
    assert_eq!(signals[at("bent.x")], vec![-(index("ch1") as f64 + 1.0); 3]);
    assert_eq!(signals[at("bent.y")], vec![index("ch3") as f64 + 1.0; 3]);
    let sensors = config.build_sensors(&model).unwrap();
    let (_, ch11) = sensors.iter().find(|(n, _)| n == "ch11").unwrap();
    assert_eq!(ch11.direction(), [-1.0, 0.0, 0.0]);
    let anchors = groups.anchors(&model);
    let anchor = |name: &str| anchors[groups.names().iter().position(|g| g == name).unwrap()].unwrap();
    // The bent's footings straddle x = 44.5 m at 8.97 m below the deck; the
    // abutments' soffit edges are centred on their support lines.
    let bent = anchor("bent");
    assert!(
        (bent[0] - 44.5).abs() < 1e-9 && bent[1].abs() < 1e-9 && (bent[2] + 8.965).abs() < 1e-9,
        "{bent:?}"
    );
    let (west, east) = (anchor("west"), anchor("east"));
    assert!(
        west[0].abs() < 1e-9 && (east[0] - 80.8).abs() < 1e-9,
        "{west:?} {east:?}"
    );
    let bad = text.replacen(
        "support = \"bent\"\ndirection = \"-x\"",
        "support = \"bent\"\ndirection = \"-w\"",
        1,
    );
    let message = Config::from_toml(&bad).unwrap_err().to_string();
    assert!(message.contains("direction") && message.contains("\"-x\""), "{message}");
}

/// Loss factors: a held one enters the damping, an updated one becomes
/// `<name>.eta` (a ratio, its own family); a run of tied bearings shares
/// its leader's (one loss site over the run's springs), and a tied bearing
/// may not give its own.
#[test]
fn loss_factors_enter_the_damping_and_the_parameters() {
    let base = include_str!("../../../config/examples/deck-on-bent.toml");
    let lossy = WEST_ABUTMENT.replacen(
        "update = [\"ry\"]",
        "update = [\"ry\"]\nloss_factor = { value = 0.2, bounds = [0.0, 0.6] }",
        1,
    );
    let config = Config::from_toml(&format!("{base}\n{lossy}")).unwrap();
    config.validate().unwrap();
    assert_eq!(config.build_damping().unwrap().loss_factors(), &[0.2]);
    let parameters = config.build_parameters().unwrap();
    let eta = parameters.iter().find(|p| p.name == "west_abutment.eta").unwrap();
    assert_eq!(eta.kind, ParameterKind::LossFactor { field: 0, count: 1 });
    assert_eq!((eta.lower, eta.upper), (0.0, 0.6));
    assert_eq!(
        config.parameter_family(&eta.name),
        Some(crate::config::ParameterFamily::LossFactor)
    );
    let held = Config::from_toml(&format!(
        "{base}\n{}",
        WEST_ABUTMENT.replacen("update", "loss_factor = 0.1\nupdate", 1)
    ))
    .unwrap();
    assert!(held
        .build_parameters()
        .unwrap()
        .iter()
        .all(|p| p.name != "west_abutment.eta"));
    assert_eq!(held.build_damping().unwrap().loss_factors(), &[0.1]);

    let painter = include_str!("../../../config/painter-street.toml");
    let leader = "tie = \"west_south\"";
    let with_leader = painter.replacen(
        "name = \"west_south\"",
        "name = \"west_south\"\nloss_factor = { value = 0.3, bounds = [0.0, 1.0] }",
        1,
    );
    let config = Config::from_toml(&with_leader).unwrap();
    let eta: Vec<_> = config
        .build_parameters()
        .unwrap()
        .into_iter()
        .filter(|p| p.name.ends_with(".eta"))
        .collect();
    assert_eq!(eta.len(), 1, "{eta:?}");
    assert_eq!(eta[0].kind, ParameterKind::LossFactor { field: 0, count: 1 });
    assert_eq!(config.build_damping().unwrap().loss_factors(), &[0.3]);
    // The leader and the bearings tied to it, three springs each.
    let sites = config.loss_sites().unwrap();
    let run = 1 + config
        .model
        .bearings
        .iter()
        .filter(|b| b.tie.as_deref() == Some("west_south"))
        .count();
    let springs: usize = config.model.springs.iter().map(|s| s.stiffness.len()).sum();
    let first = springs
        + 3 * config
            .model
            .bearings
            .iter()
            .position(|b| b.name == "west_south")
            .unwrap();
    assert!(run >= 2);
    assert_eq!(sites[0].springs, (first..first + 3 * run).collect::<Vec<_>>());
    let own = with_leader.replacen(leader, &format!("{leader}\nloss_factor = 0.1"), 1);
    let message = Config::from_toml(&own).unwrap().validate().unwrap_err().to_string();
    assert!(
        message.contains("loss_factor: a tied bearing takes the loss factor of \"west_south\""),
        "{message}"
    );
}

/// Two abutments on one soil: `east_abutment` tied to `west_abutment` on
/// Painter Street's whole bridge shares its updated components and its loss
/// factor (one parameter each over the two supports' κ fields); each
/// mismatch is refused naming the tied support's key.
#[test]
fn supports_tie_into_one_soil() {
    let base = include_str!("../../../config/painter-street-bridge.toml");
    let east = "name = \"east_abutment\"\nedge = { patch = \"bottom_slab.span2\", edge = \"xi1\" }\nsupport = \"east\"\nstiffness = { x = 1.556e+08, y = 3.113e+07, z = 3.891e+09, ry = 1.297e+10 }\nbounds = [1.0e5, 1.0e12]\nupdate = [\"y\", \"ry\"]\nloss_factor = { value = 0.3, bounds = [0.0, 1.5] }\n";
    assert!(base.contains(east));
    let tied_east = east
        .replace("bounds = [1.0e5, 1.0e12]\n", "tie = \"west_abutment\"\n")
        .replace("loss_factor = { value = 0.3, bounds = [0.0, 1.5] }\n", "");
    let with = |entry: &str| {
        let cfg = Config::from_toml(&base.replace(east, entry))?;
        cfg.validate().map(|()| cfg)
    };
    let cfg = with(&tied_east).unwrap();
    let parameters = cfg.build_parameters().unwrap();
    let named = |name: &str| parameters.iter().find(|p| p.name == name).map(|p| p.kind);
    let field = cfg.model.springs.len() + cfg.model.bearings.len();
    assert_eq!(
        named("west_abutment.y"),
        Some(ParameterKind::SpringRun {
            field,
            count: 2,
            coefficient: 1
        })
    );
    assert_eq!(
        named("west_abutment.ry"),
        Some(ParameterKind::SpringRun {
            field,
            count: 2,
            coefficient: 3
        })
    );
    assert_eq!(
        named("west_abutment.eta"),
        Some(ParameterKind::LossFactor { field: 0, count: 1 })
    );
    // One loss site over both supports' four components.
    let first: usize =
        cfg.model.springs.iter().map(|s| s.stiffness.len()).sum::<usize>() + 3 * cfg.model.bearings.len();
    let sites = cfg.loss_sites().unwrap();
    assert_eq!(sites.len(), 1);
    assert_eq!(sites[0].springs, (first..first + 8).collect::<Vec<_>>());
    assert!(
        parameters.iter().all(|p| !p.name.starts_with("east_abutment")),
        "{parameters:?}"
    );
    let untied = Config::from_toml(base).unwrap().build_parameters().unwrap();
    assert_eq!(parameters.len() + 3, untied.len());
    for (entry, why) in [
        (
            tied_east.replace("tie = \"west_abutment\"", "tie = \"footings\""),
            "must be the support just before",
        ),
        (
            tied_east.replace("y = 3.113e+07", "y = 4.0e+07"),
            "the same components with the same stiffness",
        ),
        (
            tied_east.replace("update = [\"y\", \"ry\"]", "update = [\"y\"]"),
            "updates the same ones",
        ),
        (
            format!("{tied_east}bounds = [1.0, 2.0]\n"),
            "takes the bounds of \"west_abutment\"",
        ),
        (
            format!("{tied_east}loss_factor = 0.2\n"),
            "takes the loss factor of \"west_abutment\"",
        ),
    ] {
        let e = with(&entry).unwrap_err().to_string();
        assert!(e.contains("model.supports[1]") && e.contains(why), "{entry}: {e}");
    }
}

/// One modulus over both spans: a constant field on each patch of the deck
/// on a bent, the second tied to the first, is one parameter
/// (`StiffnessRun` over both fields); a tied field that is not just after
/// its leader, has other start values or its own bounds is refused by its
/// key.
#[test]
fn stiffness_fields_tie_into_one_modulus() {
    let base = include_str!("../../../config/examples/deck-on-bent.toml");
    let field = |name: &str, patch: &str, extra: &str| {
        format!(
            "\n[[model.stiffness_fields]]\nname = \"{name}\"\npatch = \"{patch}\"\nknots_xi = [0.0, 1.0]\ndegree_xi = 0\nknots_eta = [0.0, 1.0]\ndegree_eta = 0\n{extra}"
        )
    };
    let with = |fields: String| {
        let cfg = Config::from_toml(&format!("{base}{fields}"))?;
        cfg.validate().map(|()| cfg)
    };
    let tied = field("modulus", "span1", "bounds = [0.5, 1.5]\n") + &field("modulus2", "span2", "tie = \"modulus\"\n");
    let cfg = with(tied.clone()).unwrap();
    let fields: Vec<_> = cfg
        .build_parameters()
        .unwrap()
        .into_iter()
        .filter(|p| p.name.starts_with("modulus"))
        .collect();
    assert_eq!(fields.len(), 1, "{fields:?}");
    assert_eq!(fields[0].name, "modulus.s1");
    assert_eq!(
        fields[0].kind,
        ParameterKind::StiffnessRun {
            field: 0,
            count: 2,
            coefficient: 0
        }
    );
    assert_eq!(cfg.build_model().unwrap().stiffness_fields.len(), 2);
    for (fields, why) in [
        (
            field("modulus2", "span2", "tie = \"modulus\"\n") + &field("modulus", "span1", "bounds = [0.5, 1.5]\n"),
            "must be the field just before",
        ),
        (
            tied.replace("tie = \"modulus\"\n", "tie = \"modulus\"\ncoefficients = [0.9]\n"),
            "the same start values",
        ),
        (
            tied.replace("tie = \"modulus\"\n", "tie = \"modulus\"\nbounds = [0.1, 2.0]\n"),
            "takes the bounds of \"modulus\"",
        ),
        (
            tied.replace("tie = \"modulus\"\n", "tie = \"modulus\"\nupdate = false\n"),
            "both updated",
        ),
    ] {
        let e = with(fields.clone()).unwrap_err().to_string();
        assert!(
            e.contains("model.stiffness_fields[") && e.contains(".tie") && e.contains(why),
            "{fields}: {e}"
        );
    }
}
