//! A structure on its support groups, whatever its parameters' values: the
//! nodes each group's supports hold and the ground each follows (`ℓ`),
//! found once per model and reused by every evaluation of an update
//! ([`super::SupportMotion::with_state`]).

use super::ground_forces::GroundLifts;
use super::GroundInput;
use crate::model::supports::{SupportError, SupportGroups};
use crate::model::BridgeModel;

/// The structure, its support groups and their constraint lifts.
#[derive(Debug, Clone)]
pub struct GroundedStructure {
    structure: BridgeModel,
    groups: SupportGroups,
    lifts: GroundLifts,
}

impl GroundedStructure {
    /// `structure` on `groups`; a node held by two groups' supports is
    /// refused (it cannot follow two grounds).
    pub fn new(structure: BridgeModel, groups: SupportGroups) -> Result<Self, SupportError> {
        let lifts = GroundLifts::new(&structure, &groups)?;
        Ok(Self {
            structure,
            groups,
            lifts,
        })
    }

    pub fn structure(&self) -> &BridgeModel {
        &self.structure
    }

    pub fn groups(&self) -> &SupportGroups {
        &self.groups
    }

    pub(super) fn lifts(&self) -> &GroundLifts {
        &self.lifts
    }

    /// The inputs name groups and axes that exist.
    pub fn check_inputs(&self, inputs: &[GroundInput]) -> Result<(), SupportError> {
        let count = self.groups.names().len();
        match inputs.iter().position(|i| i.group >= count || i.axis > 2) {
            Some(index) => Err(SupportError::Input {
                index,
                group: inputs[index].group,
                axis: inputs[index].axis,
                count,
            }),
            None => Ok(()),
        }
    }
}
