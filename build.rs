//! Compiles the C layer between this crate and PETSc (`csrc/petsc_amg.c`) when the `petsc`
//! feature is on, and its MPI part (`csrc/petsc_mpi.c`) when the `mpi` feature is; without them
//! there is nothing to build.

fn main() {
    #[cfg(feature = "petsc")]
    petsc::build();
}

#[cfg(feature = "petsc")]
mod petsc {
    pub fn build() {
        println!("cargo:rerun-if-changed=csrc/petsc_amg.c");
        let found = |name: &str| pkg_config::Config::new().cargo_metadata(true).probe(name);
        let petsc = found("PETSc").or_else(|_| found("petsc")).unwrap_or_else(|e| {
            panic!(
                "the `petsc` feature needs PETSc and pkg-config (Debian: apt-get install libpetsc-real-dev \
                 pkg-config): {e}"
            )
        });
        // PETSc's headers include <mpi.h>, which its .pc file does not point to on Debian.
        let mpi = found("mpi").or_else(|_| found("ompi")).ok();
        let mut c = cc::Build::new();
        c.file("csrc/petsc_amg.c").warnings(true);
        if cfg!(feature = "mpi") {
            // The MPI calls of csrc/petsc_mpi.c link against libmpi (the `mpi` probe above).
            println!("cargo:rerun-if-changed=csrc/petsc_mpi.c");
            assert!(
                mpi.is_some(),
                "the `mpi` feature needs MPI's pkg-config file (Debian: apt-get install libopenmpi-dev)"
            );
            c.file("csrc/petsc_mpi.c");
            // Scotch's random generator, reset before each partition (its headers and library
            // come with libpetsc-real-dev's libptscotch-dev).
            println!("cargo:rustc-link-lib=ptscotch");
        }
        for path in petsc
            .include_paths
            .iter()
            .chain(mpi.iter().flat_map(|m| &m.include_paths))
        {
            c.include(path);
        }
        c.compile("tc_petsc_amg");
    }
}
