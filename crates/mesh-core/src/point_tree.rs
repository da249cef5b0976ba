//! Exact nearest-point queries on a fixed cloud of 3-D points: a k-d tree over the cloud's
//! indices (median splits on the axis of largest extent, stored implicitly in one permuted index
//! array), searched depth first, the far side of a split visited only when the split plane is
//! no farther than the best point found. The answer is the one a scan of the cloud in index
//! order gives: the lowest index among the nearest points, by the same squared distances.
//!
//! Finite points only: a non-finite coordinate has no place on a split.

use nalgebra::Vector3;

/// Ranges this short are scanned instead of split.
const LEAF: usize = 8;

/// A k-d tree over `points` (borrowed; see the module documentation).
pub struct PointTree<'a> {
    points: &'a [Vector3<f64>],
    /// The cloud's indices, each range's median at its middle.
    order: Vec<u32>,
    /// The split axis of the range whose middle is at this position.
    axis: Vec<u8>,
}

impl<'a> PointTree<'a> {
    /// The tree of `points` (at most `u32::MAX` of them).
    pub fn new(points: &'a [Vector3<f64>]) -> PointTree<'a> {
        assert!(points.len() <= u32::MAX as usize, "a point tree holds at most 2^32 - 1 points");
        let mut tree = PointTree { points, order: (0..points.len() as u32).collect(), axis: vec![0; points.len()] };
        tree.build(0, points.len());
        tree
    }

    fn build(&mut self, lo: usize, hi: usize) {
        if hi - lo <= LEAF {
            return;
        }
        let (mut min, mut max) = (Vector3::repeat(f64::INFINITY), Vector3::repeat(f64::NEG_INFINITY));
        for &i in &self.order[lo..hi] {
            let p = &self.points[i as usize];
            min = min.inf(p);
            max = max.sup(p);
        }
        let axis = (max - min).imax();
        let mid = (lo + hi) / 2;
        let points = self.points;
        self.order[lo..hi].select_nth_unstable_by(mid - lo, |&a, &b| points[a as usize][axis].total_cmp(&points[b as usize][axis]));
        self.axis[mid] = axis as u8;
        self.build(lo, mid);
        self.build(mid + 1, hi);
    }

    /// The index of the point nearest to `q` (the lowest of equally near ones); `None` for an
    /// empty cloud.
    pub fn nearest(&self, q: &Vector3<f64>) -> Option<usize> {
        let mut best = (f64::INFINITY, u32::MAX);
        self.search(0, self.points.len(), q, &mut best);
        (best.1 != u32::MAX).then_some(best.1 as usize)
    }

    fn consider(&self, i: u32, q: &Vector3<f64>, best: &mut (f64, u32)) {
        let d = (self.points[i as usize] - q).norm_squared();
        if d < best.0 || (d == best.0 && i < best.1) {
            *best = (d, i);
        }
    }

    fn search(&self, lo: usize, hi: usize, q: &Vector3<f64>, best: &mut (f64, u32)) {
        if hi - lo <= LEAF {
            for &i in &self.order[lo..hi] {
                self.consider(i, q, best);
            }
            return;
        }
        let mid = (lo + hi) / 2;
        let (i, axis) = (self.order[mid], self.axis[mid] as usize);
        self.consider(i, q, best);
        let diff = q[axis] - self.points[i as usize][axis];
        let (near, far) = if diff < 0.0 { ((lo, mid), (mid + 1, hi)) } else { ((mid + 1, hi), (lo, mid)) };
        self.search(near.0, near.1, q, best);
        // Every point beyond the plane is at least `diff` away along the axis (rounding is
        // monotone, so this holds for the computed squares too); equal distances are visited
        // for the lower index.
        if diff * diff <= best.0 {
            self.search(far.0, far.1, q, best);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scan(cloud: &[Vector3<f64>], q: &Vector3<f64>) -> Option<usize> {
        let mut best: Option<(f64, usize)> = None;
        for (i, p) in cloud.iter().enumerate() {
            let d = (p - q).norm_squared();
            if best.is_none_or(|(b, _)| d < b) {
                best = Some((d, i));
            }
        }
        best.map(|(_, i)| i)
    }

    /// A deterministic stream of numbers in [0, 1).
    fn uniform(seed: &mut u64) -> f64 {
        *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (*seed >> 11) as f64 / (1u64 << 53) as f64
    }

    /// On clouds of random points, of points on a coarse lattice (many exact ties, many points
    /// on every split plane) and of repeated points, the tree answers every query as a scan in
    /// index order does.
    #[test]
    fn answers_every_query_as_a_scan_in_index_order() {
        let mut seed = 7;
        let random: Vec<Vector3<f64>> = (0..2000).map(|_| Vector3::new(uniform(&mut seed), uniform(&mut seed), 0.1 * uniform(&mut seed))).collect();
        let lattice: Vec<Vector3<f64>> = (0..1500).map(|_| Vector3::new((uniform(&mut seed) * 6.0).floor(), (uniform(&mut seed) * 4.0).floor(), 0.0)).collect();
        let repeated = vec![Vector3::new(1.0, 2.0, 3.0); 40];
        for cloud in [random, lattice, repeated] {
            let tree = PointTree::new(&cloud);
            for _ in 0..500 {
                let q = Vector3::new(uniform(&mut seed) * 6.0 - 0.5, uniform(&mut seed) * 4.0 - 0.5, uniform(&mut seed) - 0.5);
                assert_eq!(tree.nearest(&q), scan(&cloud, &q), "query {q:?}");
            }
            // The cloud's own points, each (or an earlier twin) its own nearest.
            for q in &cloud {
                assert_eq!(tree.nearest(q), scan(&cloud, q));
            }
        }
    }

    #[test]
    fn an_empty_cloud_has_no_nearest_point() {
        assert_eq!(PointTree::new(&[]).nearest(&Vector3::zeros()), None);
        assert_eq!(PointTree::new(&[Vector3::new(1.0, 0.0, 0.0)]).nearest(&Vector3::zeros()), Some(0));
    }
}
