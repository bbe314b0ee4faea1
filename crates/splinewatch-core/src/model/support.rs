//! One support of a bridge, whatever its kind: a spring field under a
//! patch, a discrete bearing, or an elastic support (along an edge, at a
//! point, at beam nodes). Each holds the structure to its support group's
//! ground through stiffness coefficients κ, which updating may take
//! (`∂K/∂κ_j`, eq. (15) of the paper for the fields).
//!
//! [`BridgeModel::supports`] is the one place that orders them: spring
//! fields, then bearings, then elastic supports. The assembled models'
//! `∂K/∂κ` vectors, the coefficient vectors, the support groups' flat
//! index and the loss sites all follow it.

use crate::geometry::vec3::Vec3;
use crate::model::bearings::Bearing;
use crate::model::elastic_supports::{ElasticSupport, SupportSite};
use crate::model::springs::SpringField;
use crate::model::BridgeModel;

/// A support of a [`BridgeModel`], with its index among those of its kind.
#[derive(Debug, Clone, Copy)]
pub enum Support<'a> {
    /// A spring field under a patch (a distributed foundation, eq. (15)).
    Field(usize, &'a SpringField),
    /// A discrete bearing at a point of a patch.
    Bearing(usize, &'a Bearing),
    /// Springs per metre along an edge, at a point or at beam nodes, with
    /// rotational components.
    Elastic(usize, &'a ElasticSupport),
}

impl<'a> Support<'a> {
    /// The support's stiffness coefficients κ, in the order of its
    /// `∂K/∂κ` blocks.
    pub fn stiffness(&self) -> &'a [f64] {
        match self {
            Self::Field(_, f) => f.stiffness(),
            Self::Bearing(_, b) => b.stiffness(),
            Self::Elastic(_, s) => s.stiffness(),
        }
    }

    /// The patch it acts on (`None`: an elastic support at beam nodes).
    pub fn patch(&self) -> Option<usize> {
        match self {
            Self::Field(_, f) => Some(f.patch()),
            Self::Bearing(_, b) => Some(b.at().patch),
            Self::Elastic(_, s) => s.patch(),
        }
    }

    /// The points where it holds `model`: a bearing's point, an elastic
    /// support's edge control points, point or beam nodes; `None` for a
    /// spring field, which holds a whole face.
    pub fn holds(&self, model: &BridgeModel) -> Option<Vec<Vec3>> {
        match self {
            Self::Field(..) => None,
            Self::Bearing(_, b) => Some(vec![model.position_of(b.at())]),
            Self::Elastic(_, s) => Some(match s.site() {
                SupportSite::Edge { patch, edge } => {
                    let shell = &model.patches[*patch].shell;
                    let net = shell.surface().points();
                    edge.control_points(shell).iter().map(|&c| net[c]).collect()
                }
                SupportSite::Point(at) => vec![model.position_of(*at)],
                SupportSite::BeamNodes(nodes) => nodes.iter().map(|&n| model.beams.position(n)).collect(),
            }),
        }
    }
}

impl BridgeModel {
    /// Every support, in the assembled models' order: spring fields, then
    /// bearings, then elastic supports.
    pub fn supports(&self) -> impl Iterator<Item = Support<'_>> + '_ {
        let fields = self.springs.iter().enumerate().map(|(k, f)| Support::Field(k, f));
        let bearings = self.bearings.iter().enumerate().map(|(k, b)| Support::Bearing(k, b));
        let elastic = self
            .elastic_supports
            .iter()
            .enumerate()
            .map(|(k, s)| Support::Elastic(k, s));
        fields.chain(bearings).chain(elastic)
    }

    /// How many supports [`Self::supports`] gives.
    pub fn support_count(&self) -> usize {
        self.supports().count()
    }
}
