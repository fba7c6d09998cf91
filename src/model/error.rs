//! The errors of building a problem: parts the mesh lacks, loads on the wrong part, initial
//! data outside the spaces, and the mesh's and loads' own.

/// Why a problem cannot be built, or a load not evaluated.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    /// A boundary part the mesh does not have.
    #[error("the mesh has no boundary part `{name}` (named for {role}); its parts are {known:?}")]
    UnknownPart {
        role: String,
        name: String,
        known: Vec<String>,
    },
    /// A traction or pressure on a part that is not a Neumann part.
    #[error("`{label}` acts on `{part}`, which is not a Neumann part (those are {neumann:?})")]
    LoadOffNeumann {
        label: String,
        part: String,
        neumann: Vec<String>,
    },
    /// Initial data outside E^h: not zero on Γ_D, a normal component on Γ_C, or across a
    /// symmetry plane.
    #[error(
        "`{label}` is not admissible at node {node} (x = {x:?}): {value:?} must vanish on Γ_D and have no \
         normal component on Γ_C or across a symmetry plane"
    )]
    InitialNotAdmissible {
        label: String,
        node: usize,
        x: [f64; 3],
        value: Vec<f64>,
    },
    /// Nodal initial fields whose sizes are not the mesh's.
    #[error("`{label}` has fields of {found:?} values, but the mesh needs {expected:?} (u₀, u₁, θ₀)")]
    InitialFieldSizes {
        label: String,
        found: Vec<usize>,
        expected: Vec<usize>,
    },
    /// Two boundary parts given roles share facets (one facet in two physical groups).
    #[error(
        "the boundary parts `{first}` and `{second}` share facets: give each facet one role (in Gmsh, put it in one physical group)"
    )]
    PartsShareFacets { first: String, second: String },
    /// A symmetry part that is not flat.
    #[error("the symmetry part `{part}` is not flat (a symmetry plane needs one normal)")]
    CurvedSymmetryPart { part: String },
    /// A contact or symmetry part without facets.
    #[error("the {role} part `{part}` has no facets (an empty physical group?): a {role} part needs at least one")]
    EmptyPart { role: &'static str, part: String },
    /// A friction law given for a part that is not a contact part.
    #[error(
        "a friction law is given for `{part}` (friction.part), which is not a contact part (those are {contact:?})"
    )]
    FrictionOffContact { part: String, contact: Vec<String> },
    /// Per-part friction laws that leave a contact part without one.
    #[error("the contact part `{part}` has no friction law: give it one (a [[friction]] table with part = \"{part}\") or add a table without `part` for the rest")]
    NoFrictionLaw { part: String },
    /// A friction scale with more than one component.
    #[error("the friction bound S must be a scalar datum, but it has {found} components")]
    FrictionScaleComponents { found: usize },
    /// A foundation velocity datum with the wrong number of components.
    #[error("the foundation's velocity has {found} components (expected {expected})")]
    FoundationComponents { found: usize, expected: usize },
    /// A foundation velocity that is not finite at a contact node.
    #[error("the foundation's velocity is {value:?} at x = {x:?}, t = {t} (expected finite values)")]
    BadFoundationVelocity { value: [f64; 3], x: [f64; 3], t: f64 },
    /// A friction scale that is negative or not finite at a contact node.
    #[error(
        "the friction bound S is {value} at x = {x:?}, t = {t} (expected a finite, non-negative value: friction.bound)"
    )]
    BadFrictionScale { value: f64, x: [f64; 3], t: f64 },
    /// A thermal condition given twice for one part.
    #[error("the part `{part}` is given two thermal conditions: give each part at most one")]
    ThermalPartTwice { part: String },
    /// A thermal condition on a contact part.
    #[error(
        "the part `{part}` is a contact part: Γ_C has its own heat exchange law (heat_exchange), so it takes no \
         thermal condition"
    )]
    ThermalOnContact { part: String },
    /// A prescribed temperature or heat flux that is not a scalar datum.
    #[error("the {condition} on `{part}` must be a scalar datum, but it has {found} components")]
    ThermalDatum {
        part: String,
        condition: &'static str,
        found: usize,
    },
    /// A convection coefficient that is negative or not finite, or an ambient temperature that
    /// is not finite.
    #[error(
        "the convection on `{part}` has h = {coefficient}, θ_∞ = {ambient} (expected a finite h ≥ 0 and a finite θ_∞)"
    )]
    BadConvection {
        part: String,
        coefficient: f64,
        ambient: f64,
    },
    /// A prescribed temperature that is not finite at a node.
    #[error("`{label}` is {value} at x = {x:?}, t = {t} (expected a finite temperature)")]
    ThermalNotFinite {
        label: String,
        x: [f64; 3],
        t: f64,
        value: f64,
    },
    /// A cell region (given a material) the mesh does not have.
    #[error("the mesh has no cell region `{name}`; its cell regions are {known:?}")]
    UnknownRegion { name: String, known: Vec<String> },
    /// A cell in two regions given materials: which material it takes would be arbitrary.
    #[error(
        "cell {cell} (centre {centre:?}) is in both cell regions `{first}` and `{second}`, which are given materials: give a cell one material (in Gmsh, put it in one physical group)"
    )]
    CellInTwoRegions {
        cell: usize,
        centre: [f64; 3],
        first: String,
        second: String,
    },
    /// More regions given materials than the per-cell index holds.
    #[error("{count} cell regions are given materials: at most 65 534")]
    TooManyRegions { count: usize },
    /// A mesh that is not valid.
    #[error(transparent)]
    Mesh(#[from] crate::mesh::MeshError),
    /// A load that cannot be built or evaluated.
    #[error(transparent)]
    Load(#[from] crate::loads::LoadError),
    /// A share of the matrices given for another number of nodes than the mesh's.
    #[error("the owned nodes of a share of the matrices mark {found} nodes, but the mesh has {nodes}")]
    OwnedNodes { found: usize, nodes: usize },
    /// A collective operation of a distributed run that failed (MPI, PETSc).
    #[error("{operation} failed: {detail}")]
    Ranks { operation: &'static str, detail: String },
}
