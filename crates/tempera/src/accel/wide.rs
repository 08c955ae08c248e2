//! A four-wide BVH with uncompressed single-precision bounds, collapsed from a binary tree,
//! and its single-ray traversal: each node's four boxes are tested together as one 4-lane slab
//! test (structure of arrays, so the compiler emits packed SSE min/max), children are visited
//! nearest first and subtrees farther than the closest hit are skipped. The layout is the
//! "BVH4" of Wald et al. 2008 ("Getting Rid of Packets: Efficient SIMD Single-Ray Traversal
//! using Multi-branching BVHs") and Embree's (Wald et al. 2014); the box test is the slab test
//! with the far distance enlarged by `1 + 2γ₃` so that rounding never culls a box the ray
//! touches (Ize 2013, "Robust BVH Ray Traversal"; pbrt-v4 §6.1.2).

use crate::math::Vec3;
use crate::pages::PageVec;
use obvhs::bvh2::Bvh2;

/// Lanes per node.
const WIDTH: usize = 4;
/// `1 + 2γ₃`, with `γₙ = nε / (1 − nε)` and `ε` half the machine epsilon.
const FAR_SCALE: f32 = 1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);
/// A child slot in use by no child. Its box is empty (`+∞` to `−∞`), which a ray with a finite
/// origin and direction never enters (its distances there are `±∞`, never NaN); a ray that is
/// not finite could (NaN distances are left out of the test), so traversal answers such a ray
/// before it reads a node.
const EMPTY: u32 = u32::MAX;

/// One node: the four children's boxes as `[min x, max x, min y, max y, min z, max z]` lanes,
/// and per child either an inner node's index (`count == 0`) or a leaf's first primitive and
/// primitive count.
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C, align(64))]
struct Node {
    bounds: [[f32; WIDTH]; 6],
    child: [u32; WIDTH],
    count: [u32; WIDTH],
}

impl Node {
    const EMPTY: Node = Node {
        bounds: [
            [f32::INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
        ],
        child: [EMPTY; WIDTH],
        count: [0; WIDTH],
    };
}

/// What a traversal step visits next: an inner node, or a leaf's primitive range.
#[derive(Clone, Copy, Debug)]
struct Item {
    child: u32,
    count: u32,
    t: f32,
}

/// Per-ray constants of the box test.
struct BoxRay {
    o: [f32; 3],
    inv: [f32; 3],
    /// Lane of `Node::bounds` holding the entry (near) plane per axis; the exit plane is the other.
    near: [usize; 3],
}

impl BoxRay {
    fn new(o: Vec3, d: Vec3) -> Self {
        // `+ 0.0` turns a negative zero into a positive one, so that its infinite inverse and
        // the choice of planes agree.
        let d = d + Vec3::ZERO;
        let inv = [1.0 / d.x, 1.0 / d.y, 1.0 / d.z];
        let near = [0, 1, 2].map(|a| 2 * a + usize::from(inv[a] < 0.0));
        Self { o: o.into(), inv, near }
    }

    /// Entry distances of the four boxes of `node` along the ray, and which of them the ray
    /// enters within `[0, t_max]`. A NaN distance (an origin exactly on a plane parallel to
    /// the ray) leaves its axis out, which only widens the interval.
    #[inline(always)]
    fn test(&self, node: &Node, t_max: f32) -> ([f32; WIDTH], u32) {
        let mut t_near = [0.0f32; WIDTH];
        let mut t_far = [f32::INFINITY; WIDTH];
        for a in 0..3 {
            let lo = &node.bounds[self.near[a]];
            let hi = &node.bounds[self.near[a] ^ 1];
            for i in 0..WIDTH {
                let n = (lo[i] - self.o[a]) * self.inv[a];
                let f = (hi[i] - self.o[a]) * self.inv[a];
                t_near[i] = if n > t_near[i] { n } else { t_near[i] };
                t_far[i] = if f < t_far[i] { f } else { t_far[i] };
            }
        }
        let mut mask = 0;
        for i in 0..WIDTH {
            let far = t_far[i] * FAR_SCALE;
            let far = if far < t_max { far } else { t_max };
            mask |= u32::from(t_near[i] <= far) << i;
        }
        (t_near, mask)
    }
}

/// Asks the cache for both lines of node `i` ahead of its visit. A prefetch is a hint: it reads
/// nothing the program sees and cannot fault, so results are unchanged.
#[inline(always)]
fn prefetch(nodes: &[Node], i: u32) {
    #[cfg(target_arch = "x86_64")]
    if let Some(node) = nodes.get(i as usize) {
        use core::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        let p = std::ptr::from_ref(node).cast::<i8>();
        // SAFETY: `p` and `p + 64` lie within `node` (128 bytes); a prefetch never faults.
        unsafe {
            _mm_prefetch::<_MM_HINT_T0>(p);
            _mm_prefetch::<_MM_HINT_T0>(p.add(64));
        }
    }
}

/// The tree. An empty tree has no nodes.
#[derive(Clone, Debug, Default)]
pub struct Wide {
    nodes: PageVec<Node>,
}

impl Wide {
    /// Collapses `bvh2` (whose leaves index primitives directly, in order) into four-wide
    /// nodes: each node takes its binary node's two children and keeps replacing the inner
    /// child of largest surface area by its two children while it has fewer than four.
    /// Iterative, so a degenerate binary tree as deep as its primitive count needs no stack.
    pub fn collapse(bvh2: &Bvh2) -> Self {
        let Some(root) = bvh2.nodes.first() else {
            return Self::default();
        };
        let mut nodes = vec![Node::EMPTY];
        if root.is_leaf() {
            set_slot(&mut nodes[0], 0, bvh2, 0, 0);
            return Self { nodes: nodes.into() };
        }
        // (binary inner node, the wide node that becomes it)
        let mut work = vec![(0usize, 0usize)];
        while let Some((b, w)) = work.pop() {
            let first = bvh2.nodes[b].first_index as usize;
            let mut group: Vec<usize> = vec![first, first + 1];
            while group.len() < WIDTH {
                let widest = (0..group.len()).filter(|&i| !bvh2.nodes[group[i]].is_leaf()).max_by(|&x, &y| {
                    let area = |i: usize| bvh2.nodes[group[i]].aabb().half_area();
                    area(x).total_cmp(&area(y))
                });
                let Some(i) = widest else { break };
                let c = bvh2.nodes[group[i]].first_index as usize;
                group[i] = c;
                group.push(c + 1);
            }
            for (slot, &c) in group.iter().enumerate() {
                let child = if bvh2.nodes[c].is_leaf() {
                    0
                } else {
                    nodes.push(Node::EMPTY);
                    work.push((c, nodes.len() - 1));
                    nodes.len() - 1
                };
                set_slot(&mut nodes[w], slot, bvh2, c, child as u32);
            }
        }
        Self { nodes: nodes.into() }
    }

    /// Replaces each leaf's range `(first, count)` by `f(first, count)` (a range of whatever
    /// the leaves' items become), calling `f` in the order of the leaves' first items.
    pub fn remap_leaves(&mut self, mut f: impl FnMut(u32, u32) -> (u32, u32)) {
        let mut leaves: Vec<(u32, u32, u8)> = Vec::new();
        for (n, node) in self.nodes.iter().enumerate() {
            for slot in 0..WIDTH {
                if node.count[slot] > 0 {
                    leaves.push((node.child[slot], n as u32, slot as u8));
                }
            }
        }
        leaves.sort_unstable();
        for (_, n, slot) in leaves {
            let node = &mut self.nodes[n as usize];
            let slot = slot as usize;
            (node.child[slot], node.count[slot]) = f(node.child[slot], node.count[slot]);
        }
    }

    /// The nearest primitive hit: `hit(prim, t_max)` returns the distance of a hit of primitive
    /// `prim` closer than `t_max`, if any, and what to return for it.
    #[inline]
    pub fn closest<H, F>(&self, o: Vec3, d: Vec3, mut t_max: f32, mut hit: F) -> Option<H>
    where
        F: FnMut(u32, f32) -> Option<(f32, H)>,
    {
        let nodes: &[Node] = &self.nodes;
        if nodes.is_empty() || !(o.is_finite() && d.is_finite()) {
            return None;
        }
        let ray = BoxRay::new(o, d);
        let mut best = None;
        let mut stack = Stack::new();
        let mut item = Item { child: 0, count: 0, t: 0.0 };
        loop {
            if item.count == 0 {
                let node = &nodes[item.child as usize];
                let (t, mut mask) = ray.test(node, t_max);
                let slot = |i: usize| {
                    if node.count[i] == 0 {
                        prefetch(nodes, node.child[i]);
                    }
                    Item { child: node.child[i], count: node.count[i], t: t[i] }
                };
                // The hit children, nearest first (the lower slot first at equal distances);
                // the nearest is visited next, the others pushed farthest first.
                match mask.count_ones() {
                    0 => {}
                    1 => {
                        item = slot(mask.trailing_zeros() as usize);
                        continue;
                    }
                    2 => {
                        let a = mask.trailing_zeros() as usize;
                        let b = (mask & (mask - 1)).trailing_zeros() as usize;
                        let (near, far) = if t[b] < t[a] { (b, a) } else { (a, b) };
                        stack.push(slot(far));
                        item = slot(near);
                        continue;
                    }
                    _ => {
                        let mut hits = [Item { child: 0, count: 0, t: 0.0 }; WIDTH];
                        let mut n = 0;
                        while mask != 0 {
                            let i = mask.trailing_zeros() as usize;
                            mask &= mask - 1;
                            let new = slot(i);
                            let mut j = n;
                            while j > 0 && hits[j - 1].t > new.t {
                                hits[j] = hits[j - 1];
                                j -= 1;
                            }
                            hits[j] = new;
                            n += 1;
                        }
                        for h in hits[1..n].iter().rev() {
                            stack.push(*h);
                        }
                        item = hits[0];
                        continue;
                    }
                }
            } else {
                for prim in item.child..item.child + item.count {
                    if let Some((t, h)) = hit(prim, t_max) {
                        t_max = t;
                        best = Some(h);
                    }
                }
            }
            loop {
                match stack.pop() {
                    None => return best,
                    Some(next) if next.t <= t_max => {
                        item = next;
                        break;
                    }
                    Some(_) => {}
                }
            }
        }
    }

    /// Whether `blocks(prim)` holds for any primitive whose leaf the segment `[0, t_max]`
    /// enters. A node's leaves are tested before its inner children are pushed, and in no
    /// particular order: the first blocker found ends the query.
    #[inline]
    pub fn any<F: FnMut(u32) -> bool>(&self, o: Vec3, d: Vec3, t_max: f32, mut blocks: F) -> bool {
        let nodes: &[Node] = &self.nodes;
        if nodes.is_empty() || !(o.is_finite() && d.is_finite()) {
            return false;
        }
        let ray = BoxRay::new(o, d);
        let mut stack = Stack::new();
        let mut node = 0u32;
        loop {
            let n = &nodes[node as usize];
            let (_, mut mask) = ray.test(n, t_max);
            while mask != 0 {
                let i = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                if n.count[i] == 0 {
                    prefetch(nodes, n.child[i]);
                    stack.push(Item { child: n.child[i], count: 0, t: 0.0 });
                } else if (n.child[i]..n.child[i] + n.count[i]).any(&mut blocks) {
                    return true;
                }
            }
            match stack.pop() {
                Some(item) => node = item.child,
                None => return false,
            }
        }
    }
}

/// Fills child `slot` of `node` from binary node `c`: its box, and either its primitive range
/// (a leaf) or the wide node `inner` built for it.
fn set_slot(node: &mut Node, slot: usize, bvh2: &Bvh2, c: usize, inner: u32) {
    let b = &bvh2.nodes[c];
    let aabb = b.aabb();
    for a in 0..3 {
        node.bounds[2 * a][slot] = aabb.min[a];
        node.bounds[2 * a + 1][slot] = aabb.max[a];
    }
    if b.is_leaf() {
        node.child[slot] = b.first_index;
        node.count[slot] = b.prim_count;
    } else {
        node.child[slot] = inner;
        node.count[slot] = 0;
    }
}

/// The traversal stack: a fixed array for the usual depths, spilling to the heap (allocated
/// only then) for degenerate trees.
struct Stack {
    items: [Item; 32],
    len: usize,
    spill: Vec<Item>,
}

impl Stack {
    #[inline(always)]
    fn new() -> Self {
        Self { items: [Item { child: 0, count: 0, t: 0.0 }; 32], len: 0, spill: Vec::new() }
    }

    #[inline(always)]
    fn push(&mut self, item: Item) {
        if self.len < self.items.len() {
            self.items[self.len] = item;
            self.len += 1;
        } else {
            self.spill.push(item);
        }
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<Item> {
        if let Some(item) = self.spill.pop() {
            return Some(item);
        }
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        Some(self.items[self.len])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Past its fixed array the stack spills to the heap and still pops last in, first out.
    #[test]
    fn stack_spills_and_stays_last_in_first_out() {
        let mut stack = Stack::new();
        let n = 3 * stack.items.len() as u32 + 5;
        for i in 0..n {
            stack.push(Item { child: i, count: 0, t: i as f32 });
        }
        assert!(!stack.spill.is_empty());
        for i in (n / 2..n).rev() {
            assert_eq!(stack.pop().map(|item| item.child), Some(i));
        }
        stack.push(Item { child: 7777, count: 0, t: 0.0 });
        assert_eq!(stack.pop().map(|item| item.child), Some(7777));
        for i in (0..n / 2).rev() {
            assert_eq!(stack.pop().map(|item| item.child), Some(i));
        }
        assert!(stack.pop().is_none());
    }

    /// The four-lane box test agrees with a scalar slab test on random boxes and rays, and
    /// empty slots are never entered.
    #[test]
    fn box_test_agrees_with_a_scalar_slab_test() {
        let mut rng = crate::math::rng::Pcg32::new(5, 8);
        let r3 = |rng: &mut crate::math::rng::Pcg32| {
            Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - Vec3::ONE
        };
        let mut entered = 0;
        for _ in 0..20_000 {
            let mut node = Node::EMPTY;
            let mut boxes = Vec::new();
            for slot in 0..3 {
                let (a, b) = (r3(&mut rng), r3(&mut rng));
                let (lo, hi) = (a.min(b), a.max(b));
                for axis in 0..3 {
                    node.bounds[2 * axis][slot] = lo[axis];
                    node.bounds[2 * axis + 1][slot] = hi[axis];
                }
                boxes.push((lo, hi));
            }
            let o = r3(&mut rng) * 2.0;
            let d = (r3(&mut rng) - o).normalize();
            let t_max = 3.0 * rng.next_f32();
            let ray = BoxRay::new(o, d);
            let (_, mask) = ray.test(&node, t_max);
            assert_eq!(mask & 0b1000, 0, "an empty slot was entered");
            for (slot, (lo, hi)) in boxes.iter().enumerate() {
                let (mut t0, mut t1) = (0.0f32, t_max);
                for axis in 0..3 {
                    let (a, b) = ((lo[axis] - o[axis]) / d[axis], (hi[axis] - o[axis]) / d[axis]);
                    t0 = t0.max(a.min(b));
                    t1 = t1.min(a.max(b));
                }
                let scalar = t0 <= t1;
                let lanes = mask & (1 << slot) != 0;
                // The lanes may enter a box the scalar test misses by a rounding error, never
                // the other way round.
                assert!(lanes || !scalar, "a box the ray enters was culled");
                if lanes != scalar {
                    assert!((t0 - t1).abs() <= 1e-5 * t1.abs().max(1.0));
                }
                entered += usize::from(lanes);
            }
        }
        assert!(entered > 5_000, "too few boxes entered ({entered}) to mean anything");
    }
}
