//! The processes of an `mpirun` (with the `mpi` feature: rsmpi over Open MPI) as the core's
//! [`Cluster`]: gathers at rank 0 (sizes first, then the bytes), rank 0's decisions broadcast,
//! and exact integer sums (`MPI_Allreduce` with `MPI_SUM` on 64-bit integers). It counts the
//! bytes each rank hands to MPI (the payload: an all-reduce's implementation moves a small
//! multiple of it).
//!
//! MPI is initialised with `MPI_THREAD_SERIALIZED`: the render loops call it from whichever
//! worker thread runs them, never from two threads at once.

use mpi::collective::SystemOperation;
use mpi::datatype::PartitionMut;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use std::sync::atomic::{AtomicU64, Ordering};
use tempera::cluster::Cluster;

/// The world communicator of this `mpirun`.
pub struct MpiCluster {
    world: SimpleCommunicator,
    rank: usize,
    size: usize,
    /// Bytes this rank has handed to MPI calls.
    sent: AtomicU64,
}

// SAFETY: MPI is initialised with MPI_THREAD_SERIALIZED and the render loops make their
// collective calls one at a time, from one thread at a time.
unsafe impl Sync for MpiCluster {}
unsafe impl Send for MpiCluster {}

/// True when an MPI launcher started this process (Open MPI's `mpirun`, a PMI or PMIx process
/// manager such as Slurm's `srun` or MPICH's Hydra): only then is MPI initialised.
pub fn launched() -> bool {
    ["OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"].iter().any(|v| std::env::var_os(v).is_some())
}

/// Initialises MPI. The universe finalises MPI when dropped: keep it until the process ends.
pub fn initialise() -> anyhow::Result<(mpi::environment::Universe, MpiCluster)> {
    let (universe, threading) = mpi::initialize_with_threading(mpi::Threading::Serialized)
        .ok_or_else(|| anyhow::anyhow!("MPI could not be initialised"))?;
    if threading < mpi::Threading::Serialized {
        anyhow::bail!("this MPI library does not allow calls from more than one thread ({threading:?})");
    }
    let world = universe.world();
    let (rank, size) = (world.rank() as usize, world.size() as usize);
    Ok((universe, MpiCluster { world, rank, size, sent: AtomicU64::new(0) }))
}

impl Cluster for MpiCluster {
    fn rank(&self) -> usize {
        self.rank
    }

    fn size(&self) -> usize {
        self.size
    }

    fn gather(&self, mut bytes: Vec<u8>) -> Vec<Vec<u8>> {
        let root = self.world.process_at_rank(0);
        // Never an empty message (Open MPI refuses a zero-length send buffer here): a leading
        // byte, dropped at rank 0.
        bytes.insert(0, 1);
        let n = bytes.len() as u64;
        self.sent.fetch_add(8 + n, Ordering::Relaxed);
        if self.rank != 0 {
            root.gather_into(&n);
            root.gather_varcount_into(&bytes[..]);
            return Vec::new();
        }
        let mut sizes = vec![0u64; self.size];
        root.gather_into_root(&n, &mut sizes[..]);
        let counts: Vec<i32> =
            sizes.iter().map(|&s| i32::try_from(s).expect("a rank sends less than 2 GiB at once")).collect();
        let displs: Vec<i32> = counts
            .iter()
            .scan(0i32, |acc, &c| {
                let d = *acc;
                *acc += c;
                Some(d)
            })
            .collect();
        let total = sizes.iter().sum::<u64>() as usize;
        let mut buffer = vec![0u8; total];
        {
            let mut partition = PartitionMut::new(&mut buffer[..], counts, &displs[..]);
            root.gather_varcount_into_root(&bytes[..], &mut partition);
        }
        let mut out = Vec::with_capacity(self.size);
        let mut at = 0usize;
        for &s in &sizes {
            out.push(buffer[at + 1..at + s as usize].to_vec());
            at += s as usize;
        }
        out
    }

    fn broadcast(&self, value: bool) -> bool {
        self.sent.fetch_add(1, Ordering::Relaxed);
        let mut v = u8::from(value);
        self.world.process_at_rank(0).broadcast_into(&mut v);
        v != 0
    }

    fn sum(&self, values: &mut [i64]) {
        self.sent.fetch_add(8 * values.len() as u64, Ordering::Relaxed);
        let send = values.to_vec();
        self.world.all_reduce_into(&send[..], values, SystemOperation::sum());
    }

    fn bytes_sent(&self) -> u64 {
        self.sent.load(Ordering::Relaxed)
    }
}
