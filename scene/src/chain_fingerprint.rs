//! A 64-bit fingerprint of the boundary of a set of triangles, for checking in
//! O(triangles) with no hash map that two sets of triangles have the same boundary.
//!
//! The boundary of a set of triangles is a chain: every directed edge `a → b` of every
//! triangle counted +1, its reverse `b → a` counted -1, so that an edge two triangles
//! share the usual way cancels, and what is left is where the set is open (an edge from
//! a point to itself counts nothing). The crack check
//! ([`crate::watertight`]) compares such chains: a group's simplified meshlets must have
//! its children's boundary wherever a neighbour meets it.
//!
//! The fingerprint gives each grid point `v` two pseudo-random words `r(v)`, `s(v)` and
//! each directed edge the value `r(a)·s(b) − r(b)·s(a)` (wrapping): antisymmetric, so a
//! reversed edge cancels and `a → a` is zero, and additive, so the fingerprint of a
//! union is the sum of its parts'. A chain's fingerprint is a polynomial in the `r` and
//! `s` values whose coefficients are the chain's edge counts (distinct edges give
//! distinct monomials `r(a)·s(b)`), so it is zero for the empty chain and otherwise zero
//! only by coincidence, about once in 2^63. The words come from keys drawn anew for each
//! check, so no file can be written to collide; a mismatch is only ever a reason for the
//! exact check, and a match is trusted.

use std::hash::BuildHasher;

/// The keys one check uses for every grid point.
#[derive(Debug, Clone, Copy)]
pub struct ChainKeys {
    keys: [u64; 4],
}

/// `a · b` folded to 64 bits: the mixing step of foldhash and wyhash.
#[inline(always)]
fn fold(a: u64, b: u64) -> u64 {
    let p = a as u128 * b as u128;
    p as u64 ^ (p >> 64) as u64
}

impl ChainKeys {
    /// Fresh keys from the standard library's random hasher seeds.
    pub fn random() -> Self {
        let state = std::collections::hash_map::RandomState::new();
        Self {
            keys: [0u64, 1, 2, 3].map(|i| state.hash_one(i) | 1),
        }
    }

    /// Fixed keys, for reproducing a fingerprint in tests.
    pub fn fixed(seed: u64) -> Self {
        Self {
            keys: [0u64, 1, 2, 3].map(|i| fold(seed ^ 0x9e37_79b9_7f4a_7c15, i + 0x2545_f491) | 1),
        }
    }

    /// The words `(r, s)` of a grid point.
    #[inline(always)]
    pub fn point(&self, p: [u32; 3]) -> (u64, u64) {
        let xy = p[0] as u64 | (p[1] as u64) << 32;
        let z = p[2] as u64;
        (
            fold(xy ^ self.keys[0], z ^ self.keys[1]),
            fold(xy ^ self.keys[2], z ^ self.keys[3]),
        )
    }
}

/// The fingerprint of one triangle's boundary `a → b → c → a`, from its corners' words:
/// the sum of its three edges' values, which is `(b − a) × (c − a)` of the words as
/// plane vectors (two products where the sum takes three).
#[inline(always)]
pub fn triangle(a: (u64, u64), b: (u64, u64), c: (u64, u64)) -> u64 {
    let (ab, ac) = (
        (b.0.wrapping_sub(a.0), b.1.wrapping_sub(a.1)),
        (c.0.wrapping_sub(a.0), c.1.wrapping_sub(a.1)),
    );
    ab.0.wrapping_mul(ac.1)
        .wrapping_sub(ac.0.wrapping_mul(ab.1))
}

/// The fingerprint of one directed edge `a → b`.
#[inline(always)]
pub fn edge(a: (u64, u64), b: (u64, u64)) -> u64 {
    a.0.wrapping_mul(b.1).wrapping_sub(b.0.wrapping_mul(a.1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_triangle_is_its_three_edges_and_shared_edges_cancel() {
        let k = ChainKeys::fixed(7);
        let [a, b, c, d] = [[0, 0, 0], [5, 0, 0], [0, 5, 0], [5, 5, 1]].map(|p| k.point(p));
        let abc = triangle(a, b, c);
        assert_eq!(
            abc,
            edge(a, b).wrapping_add(edge(b, c)).wrapping_add(edge(c, a))
        );
        assert_eq!(edge(a, a), 0);
        assert_eq!(edge(a, b).wrapping_add(edge(b, a)), 0);
        // Two triangles sharing b–c: their sum is the quad's outline a → b → d → c → a.
        let quad = abc.wrapping_add(triangle(c, b, d));
        let outline = [edge(a, b), edge(b, d), edge(d, c), edge(c, a)]
            .into_iter()
            .fold(0u64, u64::wrapping_add);
        assert_eq!(quad, outline);
        assert_ne!(quad, abc);
        // A degenerate triangle has no boundary.
        assert_eq!(triangle(a, a, b), 0);
        // Winding matters: the reversed triangle is the negated chain.
        assert_eq!(triangle(a, c, b), abc.wrapping_neg());
    }
}
