//! How long rank 0 takes to split the 3D example's cells over the ranks, and in how much memory
//! (docs/distributed.md, "Where the replicated set-up stops scaling"): the cuboid of
//! nx × nx/4 × nx/4 hexahedra (6 tetrahedra each), its dual graph, and PT-Scotch through PETSc.
//!
//! ```sh
//! cargo build --release --features mpi --example partition_scale
//! /usr/bin/time -f "peak %M KiB" target/release/examples/partition_scale 156 2   # nx, parts
//! ```
//!
//! Things to try: more parts (`156 8`), `PETSC_OPTIONS="-mat_partitioning_ptscotch_imbalance 0.05"`.

use std::time::Instant;

use thermocontact::mesh::cuboid;
use thermocontact::partition::{dual_graph, MeshPartition};

fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .map(|a| a.parse().expect("nx and parts"))
        .collect();
    let (nx, parts) = (args.first().copied().unwrap_or(48), args.get(1).copied().unwrap_or(2));
    let mesh = cuboid([40.0, 10.0, 10.0], [nx, nx / 4, nx / 4]);
    let start = Instant::now();
    let (xadj, _) = dual_graph(&mesh);
    let graph_seconds = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let partition = MeshPartition::new(&mesh, parts).expect("PT-Scotch splits the mesh");
    let partition_seconds = start.elapsed().as_secs_f64();
    let largest = (0..parts).map(|r| partition.cells_of(r).len()).max().unwrap_or(0);
    println!(
        "nx = {nx}: {} cells, {} nodes; dual graph {graph_seconds:.2} s ({} facets shared); dual graph + \
         PT-Scotch {partition_seconds:.2} s into {parts} parts, largest part / mean {:.4}",
        mesh.n_cells(),
        mesh.n_nodes(),
        xadj[mesh.n_cells()] / 2,
        largest as f64 * parts as f64 / mesh.n_cells() as f64
    );
}
