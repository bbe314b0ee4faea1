//! `[[model.stiffness_fields]]` read and built.

use super::*;

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
