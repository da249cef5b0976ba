//! Values built on demand from an index and kept up to a number of bytes.
//!
//! [`BoundedCache::get_or_build`] returns the value of index `k`, building it on first use.
//! When the kept values' bytes exceed the limit, the least recently used ones are dropped (a
//! caller still holding one keeps it alive until it is done) and built again when asked for.
//! The builder must be a pure function of `k`: a value built twice is the same, so what is
//! dropped changes the time a run takes, never its result. Callers asking for the same `k` at
//! once wait for one build.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

type Slot<T> = Arc<OnceLock<Result<Arc<T>, String>>>;

struct Entry<T> {
    slot: Slot<T>,
    /// The value's bytes once built and counted; 0 before (or for a failed build).
    bytes: usize,
    last_used: u64,
}

struct State<T> {
    entries: HashMap<usize, Entry<T>>,
    bytes: usize,
    clock: u64,
    builds: usize,
}

/// A cache of values by index, bounded in bytes (module docs).
pub struct BoundedCache<T> {
    limit: usize,
    state: Mutex<State<T>>,
}

impl<T> BoundedCache<T> {
    /// A cache keeping values up to `limit` bytes (at least the one last built).
    pub fn new(limit: usize) -> Self {
        BoundedCache {
            limit,
            state: Mutex::new(State {
                entries: HashMap::new(),
                bytes: 0,
                clock: 0,
                builds: 0,
            }),
        }
    }

    /// The bytes the cache keeps values up to.
    pub fn limit(&self) -> usize {
        self.limit
    }

    /// Changes the limit; takes effect at the next build.
    pub fn set_limit(&mut self, limit: usize) {
        self.limit = limit;
    }

    /// How many values have been built so far (rebuilds of dropped values included).
    pub fn builds(&self) -> usize {
        self.lock().builds
    }

    /// The bytes of the values kept now.
    pub fn bytes(&self) -> usize {
        self.lock().bytes
    }

    /// The value of `k`: kept, or made by `build` and measured by `bytes`. A failed build is
    /// kept as its error (it is not retried).
    pub fn get_or_build(
        &self,
        k: usize,
        build: impl FnOnce() -> Result<T, String>,
        bytes: impl FnOnce(&T) -> usize,
    ) -> Result<Arc<T>, String> {
        let slot = {
            let mut s = self.lock();
            s.clock += 1;
            let now = s.clock;
            let e = s.entries.entry(k).or_insert_with(|| Entry {
                slot: Arc::new(OnceLock::new()),
                bytes: 0,
                last_used: now,
            });
            e.last_used = now;
            e.slot.clone()
        };
        let mut built = false;
        let value = slot
            .get_or_init(|| {
                built = true;
                build().map(Arc::new)
            })
            .clone();
        if built {
            let size = value.as_ref().map_or(0, |v| bytes(v));
            let mut s = self.lock();
            s.builds += 1;
            // The entry may have been dropped while it was built: then nothing is kept.
            if let Some(e) = s
                .entries
                .get_mut(&k)
                .filter(|e| Arc::ptr_eq(&e.slot, &slot))
            {
                e.bytes = size;
                s.bytes += size;
                self.evict(&mut s, k);
            }
        }
        value
    }

    /// Drops the least recently used built values other than `keep` until the rest fit.
    fn evict(&self, s: &mut State<T>, keep: usize) {
        while s.bytes > self.limit {
            let oldest = s
                .entries
                .iter()
                .filter(|(&j, e)| j != keep && e.bytes > 0)
                .min_by_key(|(_, e)| e.last_used)
                .map(|(&j, _)| j);
            let Some(j) = oldest else { break };
            if let Some(e) = s.entries.remove(&j) {
                s.bytes -= e.bytes;
            }
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, State<T>> {
        // A panic while the lock was held cannot leave the counts inconsistent in a way that
        // matters: they only decide what is dropped.
        self.state.lock().unwrap_or_else(|p| p.into_inner())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;

    #[test]
    fn a_value_is_built_once_while_it_fits() {
        let cache = BoundedCache::new(100);
        for _ in 0..3 {
            for k in 0..4 {
                assert_eq!(
                    *cache.get_or_build(k, || Ok(k * 10), |_| 25).unwrap(),
                    k * 10
                );
            }
        }
        assert_eq!(cache.builds(), 4);
        assert_eq!(cache.bytes(), 100);
    }

    #[test]
    fn the_least_recently_used_value_is_dropped_and_rebuilt() {
        let cache = BoundedCache::new(50);
        let get = |k: usize| *cache.get_or_build(k, || Ok(k), |_| 20).unwrap();
        get(0);
        get(1);
        get(0); // 1 is now the least recently used
        get(2); // 60 bytes: 1 goes
        assert_eq!((cache.builds(), cache.bytes()), (3, 40));
        get(0);
        get(2);
        assert_eq!(cache.builds(), 3, "0 and 2 were kept");
        assert_eq!(get(1), 1);
        assert_eq!(cache.builds(), 4, "1 was rebuilt");
    }

    #[test]
    fn a_value_larger_than_the_limit_is_kept_alone() {
        let cache = BoundedCache::new(10);
        cache.get_or_build(0, || Ok(0), |_| 5).unwrap();
        cache.get_or_build(1, || Ok(1), |_| 500).unwrap();
        assert_eq!(cache.bytes(), 500);
        cache.get_or_build(1, || Ok(1), |_| 500).unwrap();
        assert_eq!(cache.builds(), 2);
    }

    #[test]
    fn a_failed_build_is_kept_as_its_error() {
        let cache: BoundedCache<u8> = BoundedCache::new(10);
        let mut tries = 0;
        for _ in 0..2 {
            let r = cache.get_or_build(
                3,
                || {
                    tries += 1;
                    Err("bad mesh".to_string())
                },
                |_| 1,
            );
            assert_eq!(r.unwrap_err(), "bad mesh");
        }
        assert_eq!(tries, 1);
    }

    #[test]
    fn concurrent_requests_agree_and_stay_within_the_limit() {
        let cache = BoundedCache::new(64);
        let values: Vec<usize> = (0..2000usize)
            .into_par_iter()
            .map(|i| {
                *cache
                    .get_or_build(i % 37, || Ok((i % 37) * 3), |_| 16)
                    .unwrap()
            })
            .collect();
        assert!(values.iter().enumerate().all(|(i, &v)| v == (i % 37) * 3));
        assert!(cache.bytes() <= 64);
    }
}
