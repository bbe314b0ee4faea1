//! The results files' topics and their JSON Schemas: what `outputs::results`
//! writes and every reader (the `monitor` command, the Python package, the
//! guide's generated page) knows by the same names.

/// The result topics under `<prefix>/`, with their JSON Schemas.
pub const TOPICS: [(&str, &str); 9] = [
    (
        "updating/parameters",
        r#"{"type":"object","required":["time","window","converged","relative_residual","parameters"],"properties":{"time":{"type":"string","format":"date-time"},"window":{"type":"integer"},"converged":{"type":"boolean"},"relative_residual":{"type":"number"},"iterations":{"type":"integer"},"stop_reason":{"type":"string"},"condition_number":{"type":"number"},"relative_offset":{"type":["number","null"]},"parameters":{"type":"array","items":{"type":"object","properties":{"name":{"type":"string"},"value":{"type":"number"},"std":{"type":["number","null"]},"lower":{"type":"number"},"upper":{"type":"number"}}}},"correlations":{"type":"array","items":{"type":"object","properties":{"a":{"type":"string"},"b":{"type":"string"},"rho":{"type":"number"}}}},"held":{"type":"array","items":{"type":"object","properties":{"name":{"type":"string"},"reason":{"type":"string","enum":["no_gradient","at_bound","unresolved"]},"value":{"type":"number"}}}},"residues":{"type":"string","enum":["frf","modes","both"]},"blocks":{"type":"object","properties":{"frf":{"type":"object","properties":{"residues":{"type":"integer"},"chi_square":{"type":"number"}}},"modes":{"type":"object","properties":{"residues":{"type":"integer"},"chi_square":{"type":"number"}}}}},"truncation":{"type":"object","properties":{"cutoff_hz":{"type":"number"},"modes_kept":{"type":"integer"},"frf_error":{"type":["number","null"]}}}}}"#,
    ),
    (
        "updating/residue",
        r#"{"type":"object","properties":{"time":{"type":"string"},"window":{"type":"integer"},"frequency_hz":{"type":"array","items":{"type":"number"}},"frfs":{"type":"array","items":{"type":"object","properties":{"input":{"type":"string"},"output":{"type":"string"},"relative_residue":{"type":"array","items":{"type":"number"}}}}},"modes":{"type":"array","items":{"type":"object","properties":{"identified":{"type":"integer"},"model_mode":{"type":"integer"},"identified_frequency_hz":{"type":"number"},"model_frequency_hz":{"type":"number"},"relative_frequency_error":{"type":"number"},"normalised_frequency_residue":{"type":"number"},"identified_damping":{"type":"number"},"model_damping":{"type":"number"},"mac":{"type":"number"}}}}}}"#,
    ),
    (
        "updating/failures",
        r#"{"type":"object","properties":{"time":{"type":"string"},"window":{"type":"integer"},"error":{"type":"string"},"skipped":{"type":"boolean"}}}"#,
    ),
    (
        "frf/measured",
        r#"{"type":"object","properties":{"time":{"type":"string"},"window":{"type":"integer"},"quantity":{"type":"string"},"frequency_hz":{"type":"array","items":{"type":"number"}},"frfs":{"type":"array"}}}"#,
    ),
    (
        "frf/model",
        r#"{"type":"object","properties":{"time":{"type":"string"},"window":{"type":"integer"},"quantity":{"type":"string"},"frequency_hz":{"type":"array","items":{"type":"number"}},"frfs":{"type":"array"}}}"#,
    ),
    (
        "modes",
        r#"{"type":"object","properties":{"time":{"type":"string"},"window":{"type":"integer"},"modes":{"type":"array","items":{"type":"object","properties":{"index":{"type":"integer"},"frequency_hz":{"type":"number"},"damping_ratio":{"type":"number"},"kind":{"type":"string"}}}}}}"#,
    ),
    (
        "oma/modes",
        r#"{"type":"object","required":["time","window","modes"],"properties":{"time":{"type":"string","format":"date-time"},"window":{"type":"integer"},"start":{"type":"string"},"duration_s":{"type":"number"},"fs_hz":{"type":"number"},"modes":{"type":"array","items":{"type":"object","required":["frequency_hz","damping_ratio","frequency_std_hz","damping_std","shape"],"properties":{"frequency_hz":{"type":"number"},"damping_ratio":{"type":"number"},"frequency_std_hz":{"type":["number","null"]},"damping_std":{"type":["number","null"]},"shape":{"type":"array","items":{"type":"object","properties":{"sensor":{"type":"string"},"re":{"type":"number"},"im":{"type":"number"},"std":{"type":"number"}}}},"mpc":{"type":"number"},"order":{"type":"integer"},"stable_orders":{"type":"integer"},"model_mode":{"type":["integer","null"]},"model_frequency_hz":{"type":["number","null"]},"mac":{"type":["number","null"]}}}}}}"#,
    ),
    (
        "health",
        r#"{"type":"object","properties":{"time":{"type":"string"},"blocks":{"type":"integer"},"rejected":{"type":"object"},"gaps":{"type":"integer"},"windows_accepted":{"type":"integer"},"windows_skipped":{"type":"object"},"update_runs":{"type":"integer"},"update_failures":{"type":"integer"},"queue_drops":{"type":"integer"},"recording_errors":{"type":"integer"},"results_errors":{"type":"integer"},"rerun_errors":{"type":"integer"},"log_writes_dropped":{"type":"integer"}}}"#,
    ),
    (
        "windows",
        r#"{"type":"object","properties":{"index":{"type":"integer"},"start":{"type":"string"},"end":{"type":"string"},"segments_accepted":{"type":"integer"},"segments_rejected":{"type":"integer"},"mean_coherence":{"type":"array","items":{"type":"number"}},"skipped":{"type":["string","null"]},"valid_fraction":{"type":"number"},"frf_skipped":{"type":["string","null"]},"oma_skipped":{"type":["string","null"]}}}"#,
    ),
];

/// Topics written only by a config with `[monitoring]`: registered in a
/// file when first written, so other configs' files keep their bytes.
pub const MONITORING_TOPICS: [(&str, &str); 2] = [
    (
        "monitoring/status",
        r#"{"type":"object","required":["window","time","state","t2","t2_limit","mewma","mewma_limit","temperature_c","residuals"],"properties":{"window":{"type":"integer"},"time":{"type":"string","format":"date-time"},"state":{"type":"string","enum":["training","normal","outside_training_range","alarm"]},"t2":{"type":["number","null"]},"t2_limit":{"type":["number","null"]},"mewma":{"type":["number","null"]},"mewma_limit":{"type":["number","null"]},"temperature_c":{"type":["number","null"]},"residuals":{"type":"array","items":{"type":"object","properties":{"name":{"type":"string"},"standardised":{"type":"number"}}}},"temperatures":{"type":"object"},"features":{"type":"array","items":{"type":"object","properties":{"name":{"type":"string"},"value":{"type":["number","null"]}}}},"flags":{"type":"array","items":{"type":"string"}},"exceedances":{"type":"integer"},"scored_by":{"type":["string","null"]}}}"#,
    ),
    (
        "monitoring/alarm",
        r#"{"type":"object","required":["window","time","state","previous"],"properties":{"window":{"type":"integer"},"time":{"type":"string","format":"date-time"},"state":{"type":"string"},"previous":{"type":"string"},"t2":{"type":["number","null"]},"mewma":{"type":["number","null"]},"largest_residuals":{"type":"array","items":{"type":"object","properties":{"name":{"type":"string"},"standardised":{"type":"number"}}}}}}"#,
    ),
];

/// An event's summary: its `events --json` line, one per event.
pub const EVENT_SUMMARY: &str = "events/summary";
/// An event's verdict, one per judged event.
pub const EVENT_VERDICT: &str = "events/verdict";

/// Topics of `splinewatch events` (registered when first written, as the
/// monitoring ones): [`EVENT_SUMMARY`] and [`EVENT_VERDICT`].
pub const EVENT_TOPICS: [(&str, &str); 2] = [
    (
        EVENT_SUMMARY,
        r#"{"type":"object","required":["event","start","pga_ground","peak_deck","modes","parameters","forecast","verdict","skipped"],"properties":{"event":{"type":"string"},"number":{"type":"integer","minimum":0},"start":{"type":["string","null"],"format":"date-time"},"pga_ground":{"type":["number","null"]},"peak_deck":{"type":["number","null"]},"rms_deck":{"type":["number","null"]},"modes":{"type":"array","items":{"type":"object","properties":{"frequency_hz":{"type":"number"},"damping_ratio":{"type":"number"},"frequency_std_hz":{"type":["number","null"]},"damping_std":{"type":["number","null"]},"shape":{"type":"array"}}}},"parameters":{"type":"array","items":{"type":"object","properties":{"name":{"type":"string"},"value":{"type":"number"},"std":{"type":["number","null"]},"lower":{"type":"number"},"upper":{"type":"number"}}}},"forecast":{"type":["object","null"]},"forecast_model":{"type":"array","items":{"type":"object","properties":{"name":{"type":"string"},"value":{"type":"number"}}}},"forecast_channels":{"type":"array","items":{"type":"string"}},"verdict":{"type":["object","null"]},"skipped":{"type":["string","null"]},"update":{"type":["object","null"],"properties":{"model_mode_hz":{"type":["number","null"]},"model_mode_std_hz":{"type":["number","null"]},"relative_residual":{"type":"number"},"iterations":{"type":"integer"},"converged":{"type":"boolean"},"stop_reason":{"type":"string"},"evaluations":{"type":"integer"},"relative_offset":{"type":["number","null"]},"combined_inputs":{"type":"array","items":{"type":"string"}},"residues":{"type":"string","enum":["frf","modes","both"]},"paired_modes":{"type":"array","items":{"type":"object","properties":{"identified_hz":{"type":"number"},"model_hz":{"type":"number"},"mac":{"type":"number"}}}}}},"notes":{"type":"array","items":{"type":"string"}}}}"#,
    ),
    (
        EVENT_VERDICT,
        r#"{"type":"object","required":["state","outside","bands"],"properties":{"state":{"type":"string","enum":["insufficient history","normal","alarm"]},"outside":{"type":"array","items":{"type":"string"}},"bands":{"type":"array","items":{"type":"object","properties":{"feature":{"type":"string"},"value":{"type":["number","null"]},"band":{"type":["object","null"],"properties":{"predicted":{"type":"number"},"lower":{"type":"number"},"upper":{"type":"number"},"events":{"type":"integer"}}}}}}}}"#,
    ),
];

/// The name of the MCAP metadata record that says what made a results file.
pub const PROVENANCE_METADATA: &str = "splinewatch";

/// What a results file rests on (its `splinewatch` metadata record): the
/// software and its version, the topic prefix (the bridge), and the
/// configuration file's path, SHA-256 and text, so a report can name the
/// model and config a verdict was reached with. Files written before it was
/// recorded have none.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Provenance {
    pub version: String,
    pub prefix: String,
    pub structure: String,
    pub config_path: String,
    pub config_sha256: String,
    pub config_toml: String,
}

impl Provenance {
    /// The metadata record's key–value pairs.
    pub fn to_metadata(&self) -> std::collections::BTreeMap<String, String> {
        [
            ("version", &self.version),
            ("prefix", &self.prefix),
            ("structure", &self.structure),
            ("config_path", &self.config_path),
            ("config_sha256", &self.config_sha256),
            ("config_toml", &self.config_toml),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v.clone()))
        .collect()
    }

    /// Read back from a metadata record's pairs (keys it does not know ignored).
    pub fn from_metadata(m: &std::collections::BTreeMap<String, String>) -> Self {
        let get = |k: &str| m.get(k).cloned().unwrap_or_default();
        Self {
            version: get("version"),
            prefix: get("prefix"),
            structure: get("structure"),
            config_path: get("config_path"),
            config_sha256: get("config_sha256"),
            config_toml: get("config_toml"),
        }
    }
}
