//! A beam member's stiffness as a multiplier: the stiffness-field idea
//! ([`crate::model::stiffness_field`]) for a column or a pier, one
//! coefficient `θ` on a part of its elements' stiffness
//! ([`crate::model::beam::StiffnessPart`]): a cracked section's effective
//! flexural stiffness (`θ E I`), a modulus that differs from the nominal.
//!
//! The element stiffness is linear in `E A`, `G J` and (with `Φ` held) the
//! bending block, so `K(θ) = K + (θ − 1) ∂K/∂θ` with `∂K/∂θ` the member's
//! part, assembled once: the assembled models list it after the deck's
//! stiffness fields, and sensitivities, updating and ties treat it as a
//! field of one coefficient.

use thiserror::Error;

use crate::model::beam::StiffnessPart;
use crate::model::dofs::DofMap;
use crate::model::members::BeamNet;
use crate::model::shell::Assembly;
use crate::model::sparse::SparseError;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum MemberStiffnessError {
    #[error("a member's stiffness factor must be finite and positive, got {0}")]
    Factor(f64),
    #[error("beam member {member} does not exist (the model has {count})")]
    UnknownMember { member: usize, count: usize },
    #[error("beams: {0}")]
    Assembly(#[from] SparseError),
}

/// A multiplier `θ` of part of one beam member's stiffness, validated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MemberStiffness {
    /// The member ([`BeamNet::members`]).
    member: usize,
    part: StiffnessPart,
    factor: f64,
}

impl MemberStiffness {
    pub fn new(member: usize, part: StiffnessPart, factor: f64) -> Result<Self, MemberStiffnessError> {
        if !(factor.is_finite() && factor > 0.0) {
            return Err(MemberStiffnessError::Factor(factor));
        }
        Ok(Self { member, part, factor })
    }

    pub fn member(&self) -> usize {
        self.member
    }

    pub fn part(&self) -> StiffnessPart {
        self.part
    }

    /// The start value of `θ` (1: the member as its section and material
    /// give it).
    pub fn factor(&self) -> f64 {
        self.factor
    }

    /// Adds `∂K/∂θ` (the member's part at `θ = 1`) to `target` on the global
    /// dofs of `dofs`.
    pub fn derivative_into<A: Assembly>(
        &self,
        beams: &BeamNet,
        dofs: &DofMap,
        target: &mut A,
    ) -> Result<(), MemberStiffnessError> {
        if self.member >= beams.members().len() {
            return Err(MemberStiffnessError::UnknownMember {
                member: self.member,
                count: beams.members().len(),
            });
        }
        beams.add_member_stiffness(self.member, self.part, target, dofs)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::beam::{BeamMaterial, Section};
    use crate::model::members::{BeamBase, BeamMember};
    use faer::Mat;

    fn portal() -> BeamNet {
        let material = BeamMaterial::isotropic(30e9, 0.2, 2500.0).unwrap();
        let section = Section::rectangle(0.6, 0.9, 0.2).unwrap();
        let member = |name: &str, start, end, base| {
            BeamMember::new(name, (start, end), [0.0, 1.0, 0.0], section, material, 3, base).unwrap()
        };
        let members = vec![
            member("left", [0.0; 3], [0.0, 0.0, 5.0], BeamBase::Fixed),
            member("right", [8.0, 0.0, 0.0], [8.0, 0.0, 5.0], BeamBase::Fixed),
            member("girder", [0.0, 0.0, 5.0], [8.0, 0.0, 5.0], BeamBase::Free),
        ];
        BeamNet::new(members, 1e-6).unwrap()
    }

    /// The four parts of every member add up to the net's stiffness, each
    /// part is symmetric, and a missing member or a factor ≤ 0 is refused.
    #[test]
    fn the_parts_of_every_member_add_up_to_the_stiffness() {
        let net = portal();
        let (k, _) = net.matrices();
        let n = k.nrows();
        let dofs = DofMap::of_model(&[], net.node_count(), 0);
        let mut sum = Mat::<f64>::zeros(n, n);
        for member in 0..3 {
            for part in [StiffnessPart::Axial, StiffnessPart::Torsion, StiffnessPart::Bending] {
                let mut d = Mat::<f64>::zeros(n, n);
                MemberStiffness::new(member, part, 1.0)
                    .unwrap()
                    .derivative_into(&net, &dofs, &mut d)
                    .unwrap();
                assert!((&d - d.transpose()).norm_max() <= 1e-12 * d.norm_max());
                sum += &d;
            }
        }
        assert!((&sum - &k).norm_max() <= 1e-12 * k.norm_max());
        let mut all = Mat::<f64>::zeros(n, n);
        for member in 0..3 {
            MemberStiffness::new(member, StiffnessPart::All, 1.0)
                .unwrap()
                .derivative_into(&net, &dofs, &mut all)
                .unwrap();
        }
        assert!((&all - &k).norm_max() <= 1e-12 * k.norm_max());
        assert_eq!(
            MemberStiffness::new(3, StiffnessPart::All, 1.0)
                .unwrap()
                .derivative_into(&net, &dofs, &mut all),
            Err(MemberStiffnessError::UnknownMember { member: 3, count: 3 })
        );
        assert_eq!(
            MemberStiffness::new(0, StiffnessPart::All, 0.0),
            Err(MemberStiffnessError::Factor(0.0))
        );
    }
}
