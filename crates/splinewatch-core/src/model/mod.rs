//! The deck as physics and discretisation: what is assembled.
//!
//! May import: `geometry`, `linalg`.
//!
//! - [`material`]: the plane-stress Mindlin matrix `E'` (eq. 7–9);
//! - [`sparse`]: the control net's sparsity pattern and the symmetric matrices on it (eq. 16–17 at scale);
//! - [`shell`]: the degenerate shell, its displacement shapes and the one quadrature loop of eq. (16)–(17);
//! - [`constraints`]: rigid edge supports as the dof reduction `δ = T q`;
//! - [`springs`]: B-spline spring fields on a face and their `∂K/∂κ_j` (eq. 19–22);
//! - [`stiffness_field`]: B-spline multipliers of the deck's stiffness and their `∂K/∂θ_k`;
//! - [`damping`]: the damping curve ζ(f) (eq. 25–29) and the supports' loss factors;
//! - [`loss_sites`]: which spring coefficients each loss factor weighs;
//! - [`patch`]: a shell with its material and added mass;
//! - [`dofs`]: the numbering of the generalised dofs, node by node, and what each dof is;
//! - [`joints`]: rigid joints between patches by penalty coupling;
//! - [`beam`]: straight 3-D Timoshenko beam elements (columns, piers), their stiffness and consistent mass;
//! - [`members`]: beam members cut into elements, meeting where their nodes coincide, their bases held;
//! - [`elastic_supports`]: springs in six components along a patch edge (abutments, embankments), at a point of a patch or at beam nodes (footings);
//! - [`rigid`]: rigid bodies (bent caps, diaphragms, rigid offsets) that deck edges and beam nodes follow;
//! - [`bearings`]: discrete elastic bearings and point masses;
//! - [`supports`]: the support groups, which ground each support moves with.
//!
//! [`BridgeModel`] gathers them; the solvers assemble it
//! ([`crate::solvers::dense_model`], [`crate::solvers::sparse_model`]).

pub mod beam;
pub mod bearings;
pub mod constraints;
pub mod damping;
pub mod dofs;
pub mod elastic_supports;
pub mod joints;
pub mod loss_sites;
pub mod material;
pub mod member_stiffness;
pub mod members;
pub mod patch;
pub mod rigid;
pub mod shell;
pub mod sparse;
pub mod springs;
pub mod stiffness_field;
pub mod support;
pub mod supports;

use bearings::{Bearing, PointMass};
use constraints::EdgeConstraint;
use elastic_supports::ElasticSupport;
use joints::Joint;
use material::OrthotropicMaterial;
use member_stiffness::MemberStiffness;
use members::BeamNet;
use patch::Patch;
use rigid::RigidBody;
use shell::{Frame, Shell};
use springs::SpringField;
use stiffness_field::StiffnessField;

/// A bridge's physics and discretisation, validated: the deck's shell
/// patches, beam members (columns, piers), rigid bodies, and the supports
/// that hold them (spring fields, bearings, elastic supports, constraints).
/// Springs, stiffness fields, constraints, bearings and masses each name
/// their patch by index.
#[derive(Debug, Clone)]
pub struct BridgeModel {
    pub patches: Vec<Patch>,
    pub springs: Vec<SpringField>,
    /// Stiffness multiplier fields of the deck (none: the nominal material).
    pub stiffness_fields: Vec<StiffnessField>,
    /// Multipliers of beam members' stiffness; in the assembled models
    /// they follow the stiffness fields, one coefficient each.
    pub member_stiffness: Vec<MemberStiffness>,
    pub constraints: Vec<EdgeConstraint>,
    /// Rigid joints between patches ([`joints::find_joints`]).
    pub joints: Vec<Joint>,
    /// The joints' dimensionless penalty factor `c` ([`joints`]).
    pub joint_penalty: f64,
    /// Discrete bearings; their `k_x, k_y, k_z` follow the spring fields'
    /// coefficients in the assembled model.
    pub bearings: Vec<Bearing>,
    /// Springs along patch edges or at beam nodes; their components follow the bearings'
    /// coefficients in the assembled model.
    pub elastic_supports: Vec<ElasticSupport>,
    pub masses: Vec<PointMass>,
    /// Beam members (columns, piers) and their nodes, numbered after the
    /// patches' control points.
    pub beams: BeamNet,
    /// Rigid bodies; their reference nodes follow the beam nodes.
    pub rigid_bodies: Vec<RigidBody>,
}

impl Default for BridgeModel {
    /// Nothing: no patch, no beam (a frame of beams alone starts here).
    fn default() -> Self {
        Self {
            patches: Vec::new(),
            springs: Vec::new(),
            stiffness_fields: Vec::new(),
            member_stiffness: Vec::new(),
            constraints: Vec::new(),
            joints: Vec::new(),
            joint_penalty: joints::DEFAULT_PENALTY,
            bearings: Vec::new(),
            elastic_supports: Vec::new(),
            masses: Vec::new(),
            beams: BeamNet::default(),
            rigid_bodies: Vec::new(),
        }
    }
}

impl BridgeModel {
    /// One patch named `"deck"`, nothing else attached.
    pub fn new(shell: Shell, material: OrthotropicMaterial) -> Self {
        Self {
            patches: vec![Patch::new("deck", shell, material).expect("a non-empty name")],
            ..Self::default()
        }
    }

    /// The numbering of the model's generalised dofs.
    pub fn dof_map(&self) -> dofs::DofMap {
        dofs::DofMap::of_model(&self.patches, self.beams.node_count(), self.rigid_bodies.len())
    }

    pub fn dof_count(&self) -> usize {
        self.dof_map().dof_count()
    }

    /// Where `at` lies, in global coordinates (metres).
    pub fn position_of(&self, at: bearings::PatchPoint) -> crate::geometry::vec3::Vec3 {
        self.patches[at.patch].shell.position(at.xi, at.eta, at.tau)
    }

    /// The shell patches' control points (beam nodes not counted).
    pub fn control_point_count(&self) -> usize {
        self.dof_map().control_point_count()
    }

    /// The spring coefficients κ of eq. (22), one vector per support in
    /// [`Self::supports`]' order (the assembled model's).
    pub fn spring_coefficients(&self) -> Vec<Vec<f64>> {
        self.supports().map(|s| s.stiffness().to_vec()).collect()
    }

    /// The start coefficients θ of every stiffness field, then of every
    /// member's multiplier (one each): the assembled models' order.
    pub fn field_coefficients(&self) -> Vec<Vec<f64>> {
        self.stiffness_fields
            .iter()
            .map(|f| f.coefficients().to_vec())
            .chain(self.member_stiffness.iter().map(|m| vec![m.factor()]))
            .collect()
    }

    /// The shell patches' control points (their nets), in global order.
    pub fn control_point_positions(&self) -> Vec<crate::geometry::vec3::Vec3> {
        self.patches
            .iter()
            .flat_map(|p| p.shell.surface().points().iter().copied())
            .collect()
    }

    /// The director frames of every control point, in global order.
    pub fn frames(&self) -> Vec<Frame> {
        self.patches
            .iter()
            .flat_map(|p| p.shell.frames().iter().copied())
            .collect()
    }
}
