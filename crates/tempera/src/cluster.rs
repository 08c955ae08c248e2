//! The processes one render is shared among (MPI ranks, with `tempera-cli`'s `mpi` feature), as
//! the render loops see them: a rank and a size, gathering bytes at rank 0, rank 0's decisions
//! broadcast, and exact integer sums. The core stays free of MPI; a single process is [`Solo`].
//!
//! Every render loop splits its work by rank so that the image at rank 0 is bit-identical to a
//! single process's: tiles of pixel samples are merged at rank 0 in tile order, Markov chains'
//! statistics in chain order, and every splat buffer is a fixed-point integer sum.

/// One process's view of the processes it renders with.
pub trait Cluster: Sync {
    fn rank(&self) -> usize;
    fn size(&self) -> usize;
    /// Rank 0 receives every rank's `bytes` in rank order; the other ranks receive nothing.
    fn gather(&self, bytes: Vec<u8>) -> Vec<Vec<u8>>;
    /// Every rank receives rank 0's `value`.
    fn broadcast(&self, value: bool) -> bool;
    /// Replaces `values` on every rank by their element-wise sums over the ranks.
    fn sum(&self, values: &mut [i64]);
    /// Bytes this rank has handed to the exchanges so far (gathers, broadcasts, sums).
    fn bytes_sent(&self) -> u64 {
        0
    }
}

impl dyn Cluster + '_ {
    /// True on the rank that writes the results.
    pub fn is_root(&self) -> bool {
        self.rank() == 0
    }

    /// True when more than one process renders.
    pub fn is_distributed(&self) -> bool {
        self.size() > 1
    }

    /// Returns on every rank once every rank has called it (a broadcast alone does not wait:
    /// rank 0 may leave it before the others arrive).
    pub fn barrier(&self) {
        self.gather(Vec::new());
        self.broadcast(true);
    }

    /// Whether this rank does item `i` of work dealt round-robin.
    pub fn owns(&self, i: usize) -> bool {
        i % self.size() == self.rank()
    }
}

/// A single process.
#[derive(Clone, Copy, Debug, Default)]
pub struct Solo;

/// The single process every render uses unless told otherwise.
pub static SOLO: Solo = Solo;

impl Cluster for Solo {
    fn rank(&self) -> usize {
        0
    }
    fn size(&self) -> usize {
        1
    }
    fn gather(&self, bytes: Vec<u8>) -> Vec<Vec<u8>> {
        vec![bytes]
    }
    fn broadcast(&self, value: bool) -> bool {
        value
    }
    fn sum(&self, _values: &mut [i64]) {}
}

/// Little-endian encoding of what ranks send each other.
#[derive(Debug, Default)]
pub struct Wire {
    pub bytes: Vec<u8>,
}

impl Wire {
    pub fn u64(&mut self, v: u64) -> &mut Self {
        self.bytes.extend_from_slice(&v.to_le_bytes());
        self
    }
    pub fn f64(&mut self, v: f64) -> &mut Self {
        self.u64(v.to_bits())
    }
    pub fn i128(&mut self, v: i128) -> &mut Self {
        self.bytes.extend_from_slice(&v.to_le_bytes());
        self
    }
}

/// Reads what [`Wire`] wrote, in the same order.
#[derive(Debug)]
pub struct Reader<'a> {
    bytes: &'a [u8],
}

impl<'a> Reader<'a> {
    pub fn new(bytes: &'a [u8]) -> Self {
        Self { bytes }
    }
    fn take<const N: usize>(&mut self) -> [u8; N] {
        let (head, tail) = self.bytes.split_at(N);
        self.bytes = tail;
        head.try_into().expect("N bytes")
    }
    pub fn u64(&mut self) -> u64 {
        u64::from_le_bytes(self.take())
    }
    pub fn f64(&mut self) -> f64 {
        f64::from_bits(self.u64())
    }
    pub fn i128(&mut self) -> i128 {
        i128::from_le_bytes(self.take())
    }
    pub fn is_empty(&self) -> bool {
        self.bytes.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wire_round_trips_every_bit() {
        let mut w = Wire::default();
        w.u64(7).f64(-0.0).f64(f64::NAN).i128(-(1i128 << 100));
        let mut r = Reader::new(&w.bytes);
        assert_eq!(r.u64(), 7);
        assert_eq!(r.f64().to_bits(), (-0.0f64).to_bits());
        assert!(r.f64().is_nan());
        assert_eq!(r.i128(), -(1i128 << 100));
        assert!(r.is_empty());
    }
}
