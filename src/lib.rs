//! # thermocontact
//!
//! Dynamic bilateral frictional contact of a thermo-viscoelastic body with a nonmonotone
//! (velocity-weakening) friction law, discretized as in Bartosz, Danan & Szafraniec, *Numerical
//! analysis of a dynamic bilateral thermoviscoelastic contact problem with nonmonotone friction
//! law*, Comput. Math. Appl. 73 (2017) 727–746.
//!
//! ## The model (Problem 2)
//!
//! ```text
//! (1)  σ = 𝒜ε(u̇) + ℬε(u) + Cθ                  (2)  ρü = Div σ + f₀
//! (3)  ρ c_p θ̇ − div(K∇θ) = c_ij ∂u̇_i/∂x_j + g
//! (4)  σν = f₂ on Γ_N   (5) u = 0 on Γ_D   (6) θ = θ_D on Γ_D ∪ Γ_N
//! (7)  u_ν = 0 on Γ_C   (8) −σ_τ ∈ ∂j_τ(u̇_τ)   (9) −K∇θ·ν ∈ ∂j(θ) − h_τ(‖u̇_τ‖)
//! ```
//!
//! ## The scheme (Problem 14) and the solver (Problem 17)
//!
//! P1 elements for the velocity w and the temperature θ, backward Euler in time with step k,
//! u_n = u_{n−1} + k w_n. Each step is one linear system with a constant matrix
//! ([`model::StepMatrix`]) plus the nonsmooth laws on Γ_C, solved by the
//! convexification loop with an augmented-Lagrangian inner solver ([`step::PaperSolver`]). Two linear
//! paths carry it: the direct one factors the matrix once and condenses each step onto Γ_C
//! ([`step::StepSystem`], [`step::FastSolver`]); the iterative one solves each step on all
//! unknowns by Newton iterations with GMRES + ILU(0) ([`step::NewtonKrylov`]), memory linear
//! in the unknowns (`solver.linear`); where the stiffness weighs, an AMG coarse correction of
//! the velocities ([`step::VelocityAmg`], PETSc's GAMG behind the cargo feature `petsc`) keeps its
//! Krylov iterations bounded (`solver.preconditioner`).
//!
//! ## Glossary (paper symbol → identifier)
//!
//! | symbol | identifier | meaning |
//! |---|---|---|
//! | w, u, θ | `w`, `u`, `theta` | velocity, displacement, temperature |
//! | ξ, ζ | `xi`, `zeta` | friction stress, heat-exchange multiplier on Γ_C |
//! | k, n, m | `k` / `time_step`, `n`, `m` | time step, time level, convexification iterate |
//! | ℓ_i | `weight` | nodal quadrature weight ∫_ΓC φ_i |
//! | ν_i, t_{i,k} | `normal`, `tangents` | a contact node's outward normal and tangent basis ([`contact::frames`]) |
//! | T, N | `final_time`, `steps` | the time grid ([`model::TimeGrid`]) |
//! | f₀, f₂, p, g | `BodyForce`, `Traction`, `Pressure`, `HeatSource` | loads ([`model::LoadTarget`], [`loads::Datum`]) |
//! | θ_D, q, h, θ_∞ | `Temperature`, `Flux`, `Convection { coefficient, ambient }` | thermal conditions per boundary part ([`model::ThermalCondition`]) |
//! | μ(r) S | `bound` | friction bound at slip rate r |
//! | ε_conv | `tolerance` | relative tolerance of (77)–(80) |
//! | k/2^d | `cutback_depth` | substep size of a step cut back d times ([`time::Levels`]) |
//! | A, S = J A | `CsrMatrix` (A), `StepMatrix::matrix` (S) | the step matrix, and its symmetric quasi-definite form (temperature rows negated) |
//! | Ã | the Newton matrix of [`step::NewtonKrylov`] | A with the Γ_C rows of stick (w_i = 0) and slip (ξ_i = a_i + B_i w_i) nodes |
//! | A_ww, B⁻¹ | `VelocityAmg` | the velocity block of A, and one AMG V-cycle on it ([`step::VelocityAmg`]) |
//! | ℳ, 𝒦_A, 𝒦_B, G, ℳ_θ, 𝒦_θ | `mass`, `viscosity`, `elasticity`, `coupling`, `heat_mass`, `conduction` | matrices of §2 of docs/model.md |
//!
//! ## The layer map
//!
//! Each layer imports only the layers below it (`tests/layering.rs` fails on an upward import
//! or a cycle); each module's header says what it depends on.
//!
//! ```text
//!   main.rs (CLI)      python/ (PyO3)      examples/
//!   studies/     bench, verification, reproduction (the paper's figures)
//!   scenario/    TOML ⇄ typed parts: schema, load + --set overlay, validation, build; the one
//!                place that names the keys behind a failure
//!   driver/      a run: claim the folder → set up → march → finish, and its observers
//!   error        the library's error: each layer's, wrapped
//!   output/      files only: atomic writes, run folder + lock, VTU/PVD, CSV, checkpoints, figures
//!   time         the time loop with cutback levels, over the step solvers
//!   step/        one time step: the nonsmooth solvers over the direct and iterative back-ends
//!   model/       Problem + ProblemBuilder, State, the step matrix, norms (77)–(80), samples
//!   contact/ · loads/ · fem/ · material     laws and frames · data at (x, t) · P1 assembly · tensors
//!   partition    (feature `mpi`) the cells and nodes of a mesh over the ranks, the unknowns' layout
//!   la/          generic sparse linear algebra: CSC/CSR, vectors, LDLᵀ, ILU(0), GMRES, PETSc, MPI
//!   mesh/ · resources                       meshes and their checks · the memory estimate
//! ```
//!
//! The public face for a user of the library: [`Problem`] and [`ProblemBuilder`] (or
//! [`Scenario`] from TOML, or [`model::samples`] for the paper's example), [`SolverParams`],
//! [`driver::run`] for a run with its files or [`time::march`] for the bare time loop, [`State`]
//! for its fields and [`model::contact_rows`] for Γ_C, [`Error`] for what can fail. The Python
//! bindings use this face and the front doors of `mesh`, `driver` and `output`. Each folder's
//! `mod.rs` is its front door: submodules are private where nothing outside needs them, and
//! what the layers above use is re-exported there. `la`, `fem`, `loads`, `contact` and the
//! solvers of `step` are public for those who extend the crate (a law of their own, a
//! back-end, a study), not promised as stable.

pub mod contact;
pub mod driver;
pub mod error;
pub mod fem;
pub mod la;
pub mod loads;
pub mod material;
pub mod mesh;
pub mod model;
pub mod output;
#[cfg(feature = "mpi")]
pub mod partition;
pub mod resources;
pub mod scenario;
pub mod step;
pub mod studies;
pub mod time;

pub use error::{Error, Interruption};
pub use model::{Problem, ProblemBuilder, State};
pub use scenario::Scenario;
pub use step::SolverParams;
