//! The run's place among the ranks of a distributed run (`mpirun -n P`, cargo feature `mpi`;
//! docs/distributed.md), and the ranks' agreement on what each did alone.
//!
//! The ranks compute the same steps from the same numbers, so they take the same branches; what
//! one rank does alone is its files: its piece of each frame, and on rank 0 the folder's other
//! files. An error there (a full disk, a removed folder) must end every rank the same way, at
//! the same point, or the others would wait for it in their next collective call.
//! [`Ranks::agree`] is that point: one reduction after which every rank knows whether any
//! failed, and then the failing rank's message, so that the run ends as a failed step ends it
//! (the error printed once by rank 0, a non-zero status, `summary.json` saying `failed`).

use crate::error::Error;
use crate::model::Problem;
use crate::step::SolverParams;

/// This process's rank among the `size` ranks of a distributed run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Ranks {
    pub rank: usize,
    pub size: usize,
}

/// The longest message of one rank shared with the others (bytes).
#[cfg(feature = "mpi")]
const MESSAGE_BYTES: usize = 4096;

impl Ranks {
    /// The ranks of a run with `params`: `None` for one process, which decides alone.
    pub fn of(params: &SolverParams) -> Result<Option<Self>, Error> {
        if !params.krylov.distributed {
            return Ok(None);
        }
        #[cfg(feature = "mpi")]
        {
            let comm = crate::la::mpi::Communicator::world().map_err(crate::step::StepError::from)?;
            Ok(Some(Ranks {
                rank: comm.rank(),
                size: comm.size(),
            }))
        }
        // Without MPI the solver's set-up refuses a distributed run.
        #[cfg(not(feature = "mpi"))]
        Ok(None)
    }

    /// The cells of this rank's part of the run's partition of the mesh, ascending
    /// ([`Problem::partition`]: computed on the first call, which is collective, and kept for
    /// the solver's layout of the unknowns).
    pub fn own_cells(&self, problem: &Problem) -> Result<Vec<usize>, Error> {
        #[cfg(feature = "mpi")]
        {
            let comm = crate::la::mpi::Communicator::world().map_err(crate::step::StepError::from)?;
            let partition = problem.partition(&comm).map_err(crate::step::StepError::from)?;
            let mut cells: Vec<usize> = (partition.cell_part.iter().enumerate())
                .filter(|&(_, &part)| part == self.rank)
                .map(|(cell, _)| cell)
                .collect();
            // Kept by the frames' piece for the run: without the doubling's spare capacity.
            cells.shrink_to_fit();
            Ok(cells)
        }
        #[cfg(not(feature = "mpi"))]
        Ok((0..problem.mesh.n_cells()).collect())
    }

    /// Whether this is rank 0, which owns the folder.
    pub fn is_root(&self) -> bool {
        self.rank == 0
    }

    /// The ranks' outcome of something each did alone (collective: every rank calls it at the
    /// same point). Where any rank failed, every rank fails: the lowest failing rank with its
    /// own error, the others with [`OutputError::OnRank`](crate::output::OutputError::OnRank)
    /// and that rank's message. `counts`
    /// become their minimum over the ranks.
    pub fn agree(&self, local: Result<(), Error>, counts: &mut [usize]) -> Result<(), Error> {
        #[cfg(feature = "mpi")]
        {
            use crate::la::mpi::{Communicator, Reduction};
            use crate::output::OutputError;
            let la = |e| Error::from(crate::step::StepError::from(e));
            let comm = Communicator::world().map_err(la)?;
            let mut values = vec![if local.is_err() { self.rank } else { usize::MAX }];
            values.extend_from_slice(counts);
            comm.all_reduce_usize(&mut values, Reduction::Min).map_err(la)?;
            counts.copy_from_slice(&values[1..]);
            let failing = values[0];
            if failing == usize::MAX {
                return local;
            }
            let own = local
                .as_ref()
                .err()
                .filter(|_| self.rank == failing)
                .map(ToString::to_string);
            let message = text_of(&comm, own.as_deref()).map_err(la)?;
            match local {
                Err(error) if self.rank == failing => Err(error),
                _ => Err(OutputError::OnRank { rank: failing, message }.into()),
            }
        }
        #[cfg(not(feature = "mpi"))]
        {
            let _ = counts;
            local
        }
    }
}

impl Ranks {
    /// Every rank's `value`, in rank order (collective: one sum over the ranks, each adding its
    /// own entry; this rank's alone where the reduction fails).
    pub fn each(&self, value: f64) -> Vec<f64> {
        let mut values = vec![0.0; self.size];
        values[self.rank] = value;
        #[cfg(feature = "mpi")]
        {
            use crate::la::mpi::{Communicator, Reduction};
            let mut summed = values.clone();
            let reduced = Communicator::world().and_then(|comm| comm.all_reduce_f64(&mut summed, Reduction::Sum));
            if reduced.is_ok() {
                return summed;
            }
        }
        values
    }

    /// The largest `value` over the ranks (collective; this rank's where the reduction fails):
    /// the frames' seconds a run reports are its slowest rank's.
    pub fn max(&self, value: f64) -> f64 {
        #[cfg(feature = "mpi")]
        {
            use crate::la::mpi::{Communicator, Reduction};
            let mut values = [value];
            let reduced = Communicator::world().and_then(|comm| comm.all_reduce_f64(&mut values, Reduction::Max));
            if reduced.is_ok() {
                return values[0];
            }
        }
        value
    }
}

/// The `text` of the one rank that has one, on every rank (collective). Two sums over the
/// ranks, the others adding zeros: the communicator broadcasts from rank 0 only, and this runs
/// once, where a run fails.
#[cfg(feature = "mpi")]
fn text_of(comm: &crate::la::mpi::Communicator, text: Option<&str>) -> Result<String, crate::la::LaError> {
    use crate::la::mpi::Reduction;
    let bytes = text.map_or(&[][..], |t| &t.as_bytes()[..t.len().min(MESSAGE_BYTES)]);
    let mut length = [bytes.len()];
    comm.all_reduce_usize(&mut length, Reduction::Sum)?;
    let mut wide = vec![0; length[0]];
    wide.iter_mut().zip(bytes).for_each(|(w, &b)| *w = usize::from(b));
    comm.all_reduce_usize(&mut wide, Reduction::Sum)?;
    let bytes: Vec<u8> = wide.iter().map(|&w| w as u8).collect();
    Ok(String::from_utf8_lossy(&bytes).into_owned())
}
