//! Why an attempt of step 2 left S_G as it was ([`Unchanged`]): the branch of
//! appendix A (the strip), sec. 5.2 (the singular vertex) or appendix B (the new
//! curved region) that returned without a change. Reported per attempt in
//! [`crate::paper::PaperFrameStats::crumple_attempts`] (docs/paper_simulator.md, "The
//! attempts that change nothing").

/// The branch of step 2 that left S_G unchanged.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Unchanged {
    /// Appendix A: T_comp is no triangle of S_G or has no edge facing each side.
    #[default]
    NoTriangle,
    /// Appendix A: the walk entered a curved face across an edge that is no ruling
    /// (a boundary-to-boundary crease of a curved region, or a transition face).
    StripIntoCurved,
    /// Appendix A: the walk came back to a face of the strip or lost its edge.
    StripLost,
    /// The strip's curved border names no region of the layer.
    NoRegion,
    /// T_comp is narrower along v than the minimal gap: no band of rulings.
    NarrowTriangle,
    /// Fig. 6(c): the fold is shorter than three minimal gaps.
    FoldTooShort,
    /// Fig. 6(c): the split point is within 1/rho_bound of a singular vertex that is
    /// no end of the fold (our reuse rule; the paper has none).
    FoldNearSingular,
    /// Fig. 6(c): the split point is within the minimal gap of the sheet's boundary or
    /// of an S_G vertex.
    FoldPointCrowded,
    /// Fig. 6(d): the curved region's rulings are within the conflict angle of the
    /// imaginary ones (compatible, sec. 6.1).
    CompatibleRulings,
    /// Fig. 6(d): every ruling of the curved region beyond the border is flatter than
    /// theta_0 (no e_sing: sec. 5.2 makes no point there).
    FlatCurvedRegion,
    /// Fig. 6(d): none of 32 draws of chi(s) fits (inside the sheet, off S_G vertices
    /// and off the region's rulings).
    NoSingularSample,
    /// Fig. 11: no ruling of the curved region lies between F and the new point.
    NoRulingsToReplace,
    /// Fig. 24(c): both borders resolve to the same singular vertex (how each border
    /// became it; None: made by this attempt).
    SameSingular([Option<Via>; 2]),
    /// Fig. 24(c): both borders resolve to singular vertices already joined by a
    /// crease, and neither border made a new point (our rule: the region is there).
    CreaseExists([Option<Via>; 2]),
    /// Fig. 24(c): the crease between the two singular vertices would cross S_G.
    CreaseBlocked,
    /// Fig. 24(a, b): fewer than two of the band's rulings fit in S_G.
    TooFewRulings,
    /// S_G no longer meshes after the change.
    MeshFailed,
}

/// How a border of the strip became a singular vertex that existed before the attempt.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Via {
    /// Fig. 23 (bottom): the singular vertex of T_comp opposite its largest-angle edge
    /// (the paper's).
    Opposite,
    /// Fig. 6(c): the fold's split point fell within 1/rho_bound of the fold's singular
    /// end (ours: the paper splits the fold at a new point).
    FoldEnd,
    /// Fig. 6(d): the border is a ruling of a cone and its apex is taken as the border
    /// (ours: the paper adds a new point inside the cone).
    ConeApex,
    /// Fig. 6(d): the new point drawn from chi(s) fell within 1/rho_bound of an
    /// existing one, which is taken instead (ours).
    Nearby,
}
