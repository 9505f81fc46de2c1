//! What the walks tallied in chord bins share ([`crate::sphere_profile`],
//! [`crate::entry_drift`]): a value per bin read linearly between the bins' centres, and the
//! walk's result kept once per process and key.

use std::collections::HashMap;
use std::hash::Hash;
use std::sync::{Arc, Mutex, OnceLock};

/// `values` (one per bin, at increasing `centres`) at `x`: linear between centres, the end
/// bins' values beyond them; 0 when there are none.
pub(crate) fn between_centres(centres: &[f64], values: &[f64], x: f64) -> f64 {
    let n = centres.len().min(values.len());
    if n == 0 {
        return 0.0;
    }
    let i = centres[..n].partition_point(|&c| c <= x);
    if i == 0 {
        return values[0];
    }
    if i == n {
        return values[n - 1];
    }
    let (a, b) = (centres[i - 1], centres[i]);
    let t = if b > a { (x - a) / (b - a) } else { 0.0 };
    values[i - 1] + t * (values[i] - values[i - 1])
}

/// The value of `key` in `cache`, built by `build` the first time (outside the lock, so
/// another key's walk is not held up; two threads asking for one new key may both build it,
/// and the first stored is kept).
pub(crate) fn memoized<K: Eq + Hash, V, E>(
    cache: &'static OnceLock<Mutex<HashMap<K, Arc<V>>>>,
    key: K,
    build: impl FnOnce() -> Result<V, E>,
) -> Result<Arc<V>, E> {
    let cache = cache.get_or_init(Default::default);
    if let Some(v) = cache.lock().unwrap_or_else(|e| e.into_inner()).get(&key) {
        return Ok(Arc::clone(v));
    }
    let v = Arc::new(build()?);
    let mut guard = cache.lock().unwrap_or_else(|e| e.into_inner());
    Ok(Arc::clone(guard.entry(key).or_insert(v)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn between_centres_is_linear_inside_and_held_outside() {
        let (c, v) = ([1.0, 2.0, 4.0], [10.0, 20.0, 0.0]);
        assert_eq!(between_centres(&c, &v, 0.0), 10.0);
        assert_eq!(between_centres(&c, &v, 1.0), 10.0);
        assert_eq!(between_centres(&c, &v, 1.5), 15.0);
        assert_eq!(between_centres(&c, &v, 3.0), 10.0);
        assert_eq!(between_centres(&c, &v, 4.0), 0.0);
        assert_eq!(between_centres(&c, &v, 9.0), 0.0);
        assert_eq!(between_centres(&[], &[], 1.0), 0.0);
    }

    #[test]
    fn memoized_builds_once_per_key_and_passes_errors_on() {
        static CACHE: OnceLock<Mutex<HashMap<u32, Arc<u32>>>> = OnceLock::new();
        let mut builds = 0;
        for _ in 0..3 {
            let v = memoized(&CACHE, 7, || -> Result<u32, ()> {
                builds += 1;
                Ok(49)
            });
            assert_eq!(*v.unwrap(), 49);
        }
        assert_eq!(builds, 1);
        assert_eq!(
            memoized(&CACHE, 8, || Err::<u32, _>("no")).unwrap_err(),
            "no"
        );
        assert_eq!(*memoized(&CACHE, 8, || Ok::<_, ()>(64)).unwrap(), 64);
    }
}
