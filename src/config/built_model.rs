//! The model `[model]` describes, built once per model section: validating
//! a config builds it, and every later [`Config::build_model`] of the same
//! section (the FRF model, the ground parts, the modes of a run) takes a
//! copy instead of building it again.
//!
//! Kept by the section's value, not by the config: a config changed after
//! it was loaded (`monitor`, `demo` and `soak` change theirs) builds its own
//! model and is never given one built from other values.
//!
//! [`Config::build_model`]: super::Config::build_model

use splinewatch_core::model::BridgeModel;
use std::sync::{Arc, Mutex, PoisonError};

/// The last model built and the model section it was built from (as JSON),
/// shared by a config's clones.
#[derive(Debug, Clone, Default)]
pub struct BuiltModel(Arc<Mutex<Option<(String, BridgeModel)>>>);

impl BuiltModel {
    /// The model of the section `key`: a copy of the one kept when it was
    /// built from the same section, else `build()`'s, then kept. Without a
    /// key (a section JSON cannot hold), built every time.
    pub fn get_or_build<E>(
        &self,
        key: Option<String>,
        build: impl FnOnce() -> Result<BridgeModel, E>,
    ) -> Result<BridgeModel, E> {
        let Some(key) = key else {
            return build();
        };
        if let Some((kept, model)) = &*self.0.lock().unwrap_or_else(PoisonError::into_inner) {
            if *kept == key {
                return Ok(model.clone());
            }
        }
        let model = build()?;
        *self.0.lock().unwrap_or_else(PoisonError::into_inner) = Some((key, model.clone()));
        Ok(model)
    }

    /// Whether a model is kept (tests).
    #[cfg(test)]
    pub fn is_kept(&self) -> bool {
        self.0.lock().unwrap_or_else(PoisonError::into_inner).is_some()
    }
}
