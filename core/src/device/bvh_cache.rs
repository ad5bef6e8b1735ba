//! Bottom-level BVHs kept between scene builds, so that a scene built again after one
//! object changed builds only that object's BVH ([`crate::device::DeviceScene::build_cached`]).
//!
//! A BVH build is a function of its parameters (the level's kind) and its input: the
//! triangles' positions (the level's space) in input order. An entry is therefore keyed by
//! a 128-bit digest of exactly those, and a hit returns what the build would return (its CWBVH nodes and its leaf order
//! of the input triangles), bitwise. Two SipHash-1-3 digests under different keys make the
//! key; a false hit needs a 128-bit collision among the handful of levels a scene has,
//! probability about `n^2 / 2^129`.

use glam::Vec3A;
use std::collections::HashMap;
use std::hash::Hasher;
use std::sync::Arc;

/// A 128-bit digest of a BVH build's input.
pub type BuildDigest = [u64; 2];

/// One kept build: the CWBVH nodes (5 x `[u32; 4]` each, before they are rebased into the
/// node buffer) and, per leaf-ordered triangle, its index in the input.
#[derive(Debug)]
pub struct KeptBuild {
    /// CWBVH nodes as the builder made them (level-relative triangle indices).
    pub nodes: Vec<[u32; 4]>,
    /// Leaf order: input index of each ordered triangle.
    pub order: Vec<u32>,
}

/// The BVHs of the last build, by the digest of their input, and counts of builds and
/// reuses (host memory: about 28 bytes per triangle, what the device holds of them).
#[derive(Debug, Default, Clone)]
pub struct BvhCache {
    entries: HashMap<BuildDigest, Arc<KeptBuild>>,
    used: Vec<BuildDigest>,
    /// BVHs built through this cache since it was made.
    pub built: u64,
    /// BVHs taken from it since it was made.
    pub reused: u64,
}

/// The digest of a build's input: the build's kind (`build`: which parameters build it,
/// [`crate::device::device_scene::LevelBuild`] as a number), every triangle's three
/// positions' bits, in order, and the count.
pub fn build_digest(build: u64, triangles: impl Iterator<Item = [Vec3A; 3]>) -> BuildDigest {
    let mut a = std::hash::DefaultHasher::new();
    let mut b = std::hash::DefaultHasher::new();
    b.write_u64(0x9e37_79b9_7f4a_7c15); // a second key: b differs from a from the start
    a.write_u64(build);
    b.write_u64(build);
    let mut n = 0u64;
    for t in triangles {
        for p in t {
            for x in p.to_array() {
                a.write_u32(x.to_bits());
                b.write_u32(x.to_bits());
            }
        }
        n += 1;
    }
    a.write_u64(n);
    b.write_u64(n);
    [a.finish(), b.finish()]
}

impl BvhCache {
    /// The build of the input whose digest is `digest`: kept, or made by `build` and kept.
    pub fn get_or_build<E>(
        &mut self,
        digest: BuildDigest,
        build: impl FnOnce() -> Result<KeptBuild, E>,
    ) -> Result<Arc<KeptBuild>, E> {
        self.used.push(digest);
        if let Some(k) = self.entries.get(&digest) {
            self.reused += 1;
            return Ok(k.clone());
        }
        let k = Arc::new(build()?);
        self.built += 1;
        self.entries.insert(digest, k.clone());
        Ok(k)
    }

    /// Starts a scene build (what an earlier build that failed used is forgotten).
    pub fn begin_build(&mut self) {
        self.used.clear();
    }

    /// Ends a scene build: keeps only the entries it used.
    pub fn finish_build(&mut self) {
        let used: std::collections::HashSet<BuildDigest> = self.used.drain(..).collect();
        self.entries.retain(|d, _| used.contains(d));
    }

    /// Kept builds.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether nothing is kept.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn digests_tell_inputs_apart() {
        let t = [Vec3A::ZERO, Vec3A::X, Vec3A::Y];
        let u = [Vec3A::ZERO, Vec3A::X, Vec3A::Z];
        let d = build_digest(0, [t].into_iter());
        assert_eq!(d, build_digest(0, [t].into_iter()));
        assert_ne!(d, build_digest(0, [u].into_iter()));
        assert_ne!(d, build_digest(0, [t, t].into_iter()));
        assert_ne!(d[0], d[1]);
        // -0.0 and 0.0 build the same boxes but are other inputs: told apart (a miss
        // only costs a build)
        let z = [Vec3A::new(-0.0, 0.0, 0.0), Vec3A::X, Vec3A::Y];
        assert_ne!(d, build_digest(0, [z].into_iter()));
        // the same triangles built with other parameters
        assert_ne!(d, build_digest(1, [t].into_iter()));
    }

    #[test]
    fn a_build_keeps_only_what_it_used() {
        let mut c = BvhCache::default();
        let make = |n: u32| -> Result<KeptBuild, ()> {
            Ok(KeptBuild {
                nodes: vec![[n; 4]],
                order: vec![n],
            })
        };
        c.get_or_build([1, 1], || make(1)).unwrap();
        c.get_or_build([2, 2], || make(2)).unwrap();
        c.finish_build();
        assert_eq!((c.len(), c.built, c.reused), (2, 2, 0));
        let k = c.get_or_build([1, 1], || make(9)).unwrap();
        assert_eq!(k.order, vec![1]);
        c.finish_build();
        assert_eq!((c.len(), c.built, c.reused), (1, 2, 1));
        assert!(c.get_or_build([3, 3], || Err::<KeptBuild, ()>(())).is_err());
        c.finish_build();
        assert!(c.is_empty());
    }
}
