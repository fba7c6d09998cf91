//! # thermocontact
//!
//! Dynamic bilateral frictional contact of a thermo-viscoelastic body with a nonmonotone
//! (slip-weakening) friction law, discretized as in Bartosz, Danan & Szafraniec, *Numerical
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
//! ([`solver::matrix::StepMatrix`]) plus the nonsmooth laws on Γ_C, solved by the
//! convexification loop with an augmented-Lagrangian inner solver ([`solver::paper`]). Two linear
//! paths carry it: the direct one factors the matrix once and condenses each step onto Γ_C
//! ([`solver::system::StepSystem`], [`solver::fast`]); the iterative one solves each step on all
//! unknowns by Newton iterations with GMRES + ILU(0) ([`solver::newton_krylov`]), memory linear
//! in the unknowns (`solver.linear`); where the stiffness weighs, an AMG coarse correction of
//! the velocities ([`solver::amg`], PETSc's GAMG behind the cargo feature `petsc`) keeps its
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
//! | T, N | `final_time`, `steps` | the time grid ([`problem::TimeGrid`]) |
//! | f₀, f₂, p, g | `BodyForce`, `Traction`, `Pressure`, `HeatSource` | loads ([`problem::LoadTarget`], [`loads::Datum`]) |
//! | μ(r) S | `bound` | friction bound at slip rate r |
//! | ε_conv | `tolerance` | relative tolerance of (77)–(80) |
//! | k/2^d | `cutback_depth` | substep size of a step cut back d times ([`time::Levels`]) |
//! | A, S = J A | `CsrMatrix` (A), `StepMatrix::matrix` (S) | the step matrix, and its symmetric quasi-definite form (temperature rows negated) |
//! | Ã | the Newton matrix of [`solver::newton_krylov`] | A with the Γ_C rows of stick (w_i = 0) and slip (ξ_i = a_i + B_i w_i) nodes |
//! | A_ww, B⁻¹ | `VelocityAmg` | the velocity block of A, and one AMG V-cycle on it ([`solver::amg`]) |
//! | ℳ, 𝒦_A, 𝒦_B, G, ℳ_θ, 𝒦_θ | `mass`, `viscosity`, `elasticity`, `coupling`, `heat_mass`, `conduction` | matrices of §2 of docs/model.md |
//!
//! ## Module map
//!
//! [`mesh`] → [`fem`] (simplices, kernels, assembly, constrained spaces) → [`material`],
//! [`loads`] (data as constants, affine in t or expressions of x, y, z, t; P1 load vectors),
//! [`contact`] (per-node frames, laws) → [`problem`] (built by [`problem::ProblemBuilder`] from
//! typed parts: the discrete problem) → [`solver`] (step matrix, the direct and iterative linear
//! paths, nonsmooth solvers) →
//! [`time`] (the one time loop, with cutback levels k/2, k/4, … where a step fails) →
//! [`driver`] (a run: its folder, output, checkpoints and restart, progress and batch logs,
//! stopping on signals, timings, a stopped run's record) → [`output`] (files: VTK, CSV,
//! checkpoints, the run folder's lock); [`resources`] estimates a run's memory before it starts; [`scenario`] translates TOML into the builder's parts (the core never sees it),
//! [`norms`] measures; [`verification`] runs the convergence studies; [`reproduction`]
//! regenerates the paper's Section 6 (figures and the study of its open points).

pub mod bench;
pub mod contact;
pub mod driver;
pub mod error;
pub mod fem;
pub mod loads;
pub mod material;
pub mod mesh;
pub mod norms;
pub mod output;
pub mod problem;
pub mod reproduction;
pub mod resources;
pub mod scenario;
pub mod solver;
pub mod time;
pub mod verification;

pub use error::{Error, FactorStage, Interruption};
pub use problem::Problem;
pub use scenario::Scenario;
