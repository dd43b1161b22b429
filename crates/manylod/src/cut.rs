//! Many-view cuts (§3.5.2). A *node-view* pairs a tree node with a view; the cut of view V is
//! the set of node-views `(N, V)` with `c(N, V) < ε` (valid) whose parent is not valid (leaves
//! are always valid: they cannot be split). Culled node-views (`c = 0`) are part of the cut —
//! kept so later frames can start from them — but are not drawn.
//!
//! [`refine`] runs Listing 3.1 over an active list until it is empty (or for `q` iterations:
//! the lazy variant), each node-view taking at most one edge up or down per iteration:
//!
//! 1. parent not valid (or the root), node valid → into the cut (draw or cull);
//! 2. parent not valid, node not valid → all children become active (split);
//! 3. parent valid → merge: the node-view climbs to its highest valid ancestor `T` (whose
//!    parent is not valid) and, if it holds `T`'s first leaf, puts `T` into the cut; all other
//!    node-views under `T` are dropped.
//!
//! Step 3 differs from the paper, whose merge climbs one level per iteration (the first child
//! brings the parent into the active list, its sibling is dropped). That is fine when the
//! iteration runs to convergence, but the lazy variant stops early and keeps the leftovers: a
//! sibling dropped while the first child is still on its way up is lost for good when the
//! views then move and split the parent again (found by a test, see docs/manylod.md).
//! Climbing to `T` at once keeps `cut ∪ active` a partition of every view's leaves after every
//! iteration, since validity is monotone down the tree (`T` is the same for every node-view
//! under it) — so a lazy cut is always drawable and loses nothing.
//!
//! The basic cut starts from the roots ([`basic`]), the incremental one from last frame's cut.

use rayon::prelude::*;

use crate::{
    Bsh, ManyLodError,
    bsh::{first_child, parent},
    view::View,
};

/// Flag on [`NodeView::node`] in a cut (CPU and GPU) marking a culled node-view (`c = 0`):
/// kept for the next frame's incremental cut, not drawn.
pub const CULLED: u32 = 0x8000_0000;

/// A node paired with a view.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct NodeView {
    /// Node (heap index).
    pub node: u32,
    /// View index.
    pub view: u32,
}

/// A multi-cut with how it was found.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Cut {
    /// The node-views of every view's cut (drawn and culled), in no particular order.
    pub node_views: Vec<NodeView>,
    /// Iterations run.
    pub iterations: u32,
    /// Node-views processed over all iterations (the work).
    pub processed: u64,
    /// Whether the active list ran empty (false: a lazy cut that may still change).
    pub converged: bool,
    /// How many of `node_views` are culled (`c = 0`: kept for the next frame, not drawn).
    pub culled: u64,
}

/// The criterion context: tree, views, threshold.
pub struct CutProblem<'a> {
    /// The hierarchy.
    pub bsh: &'a Bsh,
    /// The views.
    pub views: &'a [View],
    /// Threshold ε in pixels.
    pub epsilon: f32,
}

impl CutProblem<'_> {
    /// Checks views and threshold.
    pub fn check(&self) -> Result<(), ManyLodError> {
        for (i, v) in self.views.iter().enumerate() {
            v.check(i)?;
        }
        if !(self.epsilon.is_finite() && self.epsilon > 0.0) {
            return Err(ManyLodError::Mismatch(format!(
                "threshold ε = {} must be positive",
                self.epsilon
            )));
        }
        Ok(())
    }

    /// `c(N, V)`.
    pub fn criterion(&self, nv: NodeView) -> f32 {
        self.views[nv.view as usize].criterion(&self.bsh.nodes[nv.node as usize])
    }

    /// Whether a node is a leaf.
    pub fn is_leaf(&self, node: u32) -> bool {
        node as usize >= self.bsh.leaf_count() - 1
    }

    /// Valid: a leaf, or `c < ε`.
    pub fn is_valid(&self, nv: NodeView) -> bool {
        self.is_leaf(nv.node) || self.criterion(nv) < self.epsilon
    }

    /// Whether the node-view is in the cut and drawn (`c > 0`), not culled.
    pub fn is_drawn(&self, nv: NodeView) -> bool {
        self.criterion(nv) > 0.0
    }

    /// The cut with its culled node-views (`c = 0`) flagged [`CULLED`], as the GPU stores it
    /// and [`crate::splat::splat`] reads it.
    pub fn flag_culled(&self, cut: &[NodeView]) -> Vec<NodeView> {
        cut.par_iter()
            .map(|&nv| NodeView {
                node: if self.is_drawn(nv) {
                    nv.node
                } else {
                    nv.node | CULLED
                },
                ..nv
            })
            .collect()
    }

    fn parent_valid(&self, nv: NodeView) -> bool {
        nv.node > 0
            && self.is_valid(NodeView {
                node: parent(nv.node),
                view: nv.view,
            })
    }

    /// Step 3 for a node-view whose parent is valid: its highest valid ancestor `T` if the
    /// node-view lies on `T`'s leftmost path (it holds `T`'s first leaf), else `None` (dropped:
    /// the node-view on that path brings `T`).
    pub fn merge_target(&self, nv: NodeView) -> Option<NodeView> {
        let mut node = nv.node;
        let mut leftmost = true;
        while self.parent_valid(NodeView { node, ..nv }) {
            leftmost &= node % 2 == 1;
            node = parent(node);
        }
        leftmost.then_some(NodeView { node, ..nv })
    }
}

/// The roots paired with every view: the start of the basic cut.
pub fn roots(views: usize) -> Vec<NodeView> {
    (0..views as u32)
        .map(|view| NodeView { node: 0, view })
        .collect()
}

/// One node-view's step of Listing 3.1: what goes to the cut and what stays active.
enum Step {
    Cut(NodeView),
    /// The node-view split: what its descendants decided in the same iteration put into the
    /// cut, what stays active, and how many descendants were processed.
    Split {
        cut: Vec<NodeView>,
        active: Vec<NodeView>,
        processed: u64,
    },
    Drop,
}

/// The most tree levels one iteration of [`refine_levels`] descends.
pub const MAX_LEVELS_PER_ITERATION: u32 = 4;

/// The children of a node-view.
fn children(nv: NodeView) -> [NodeView; 2] {
    let c = first_child(nv.node);
    [NodeView { node: c, ..nv }, NodeView { node: c + 1, ..nv }]
}

/// A split of `nv` whose descendants down to `levels − 1` levels below it are decided at once
/// (steps 1 and 2; their parents split, so none merges).
fn split(problem: &CutProblem, nv: NodeView, levels: u32) -> Step {
    let (mut cut, mut active, mut processed) = (Vec::new(), children(nv).to_vec(), 0);
    for _ in 1..levels {
        let mut next = Vec::with_capacity(2 * active.len());
        for nv in active {
            processed += 1;
            if problem.is_valid(nv) {
                cut.push(nv);
            } else {
                next.extend(children(nv));
            }
        }
        active = next;
    }
    Step::Split {
        cut,
        active,
        processed,
    }
}

/// Runs Listing 3.1 from `active` for at most `max_iterations` (`None`: until no node-view is
/// active); a lazy cut's leftover active node-views join the cut.
pub fn refine(
    problem: &CutProblem,
    active: Vec<NodeView>,
    max_iterations: Option<u32>,
) -> Result<Cut, ManyLodError> {
    refine_levels(problem, active, max_iterations, 1)
}

/// [`refine`] with iterations that descend up to `levels` tree levels (1 to
/// [`MAX_LEVELS_PER_ITERATION`]; 1 is Listing 3.1): a split's children are decided in the same
/// iteration, and theirs, down to `levels − 1` levels below it, so fewer iterations process the
/// same node-views. A converged cut is the same for every `levels`; a lazy one goes deeper.
pub fn refine_levels(
    problem: &CutProblem,
    active: Vec<NodeView>,
    max_iterations: Option<u32>,
    levels: u32,
) -> Result<Cut, ManyLodError> {
    problem.check()?;
    if !(1..=MAX_LEVELS_PER_ITERATION).contains(&levels) {
        return Err(ManyLodError::Mismatch(format!(
            "{levels} tree levels per iteration: must be 1 to {MAX_LEVELS_PER_ITERATION}"
        )));
    }
    let n = problem.bsh.nodes.len() as u32;
    if let Some(bad) = active
        .iter()
        .find(|nv| nv.node >= n || nv.view as usize >= problem.views.len())
    {
        return Err(ManyLodError::Mismatch(format!(
            "node-view {bad:?} outside {n} nodes × {} views",
            problem.views.len()
        )));
    }
    let mut cut = Cut::default();
    let mut active = active;
    while !active.is_empty() && max_iterations.is_none_or(|q| cut.iterations < q) {
        cut.iterations += 1;
        cut.processed += active.len() as u64;
        let steps: Vec<Step> = active
            .par_iter()
            .map(|&nv| {
                if !problem.parent_valid(nv) {
                    if problem.is_valid(nv) {
                        Step::Cut(nv)
                    } else {
                        split(problem, nv, levels)
                    }
                } else {
                    match problem.merge_target(nv) {
                        Some(top) => Step::Cut(top),
                        None => Step::Drop,
                    }
                }
            })
            .collect();
        active = Vec::with_capacity(steps.len());
        for s in steps {
            match s {
                Step::Cut(nv) => cut.node_views.push(nv),
                Step::Split {
                    cut: c,
                    active: a,
                    processed,
                } => {
                    cut.node_views.extend(c);
                    active.extend(a);
                    cut.processed += processed;
                }
                Step::Drop => {}
            }
        }
    }
    cut.converged = active.is_empty();
    cut.node_views.extend(active);
    cut.culled = cut
        .node_views
        .par_iter()
        .filter(|&&nv| problem.criterion(nv) == 0.0)
        .count() as u64;
    Ok(cut)
}

/// The basic cut: [`refine`] from the roots of all views until converged.
pub fn basic(problem: &CutProblem) -> Result<Cut, ManyLodError> {
    refine(problem, roots(problem.views.len()), None)
}
