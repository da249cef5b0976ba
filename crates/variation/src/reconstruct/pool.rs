//! Per-thread buffers of the fused decoder, lent by a shared pool and returned to it on drop.

use nalgebra::Vector3;

use super::fused::FusedScratch;

/// Per-thread buffers of [`FusedDecoder::decode_average_many`](super::FusedDecoder::decode_average_many).
type Buffers = (FusedScratch, Vec<Vec<Vector3<f64>>>);

/// Buffers borrowed from a pool and returned to it on drop.
pub(super) struct Pooled<'p> {
    pool: &'p std::sync::Mutex<Vec<Buffers>>,
    item: Option<Buffers>,
}

impl<'p> Pooled<'p> {
    pub(super) fn take(pool: &'p std::sync::Mutex<Vec<Buffers>>) -> Self {
        let item = pool.lock().ok().and_then(|mut p| p.pop());
        Pooled {
            pool,
            item: Some(item.unwrap_or_default()),
        }
    }

    pub(super) fn get(&mut self) -> (&mut FusedScratch, &mut Vec<Vec<Vector3<f64>>>) {
        let (s, b) = self.item.get_or_insert_with(Default::default);
        (s, b)
    }
}

impl Drop for Pooled<'_> {
    fn drop(&mut self) {
        if let (Some(item), Ok(mut p)) = (self.item.take(), self.pool.lock()) {
            p.push(item);
        }
    }
}
