//! What every backend checks of its buffers: the table of the buffers it holds (a missing
//! one is [`BackendError::MissingResource`]) and the bounds of a `Step::Write`.

use super::BackendError;
use crate::device::handle::ResourceId;
use std::collections::HashMap;

/// The buffers a backend holds, by resource id (`T`: the backend's buffer and its size).
#[derive(Debug)]
pub struct ResourceTable<T> {
    map: HashMap<ResourceId, T>,
}

impl<T> Default for ResourceTable<T> {
    fn default() -> Self {
        ResourceTable {
            map: HashMap::new(),
        }
    }
}

impl<T> ResourceTable<T> {
    /// Buffer `id`, or [`BackendError::MissingResource`] (freed or never created).
    pub fn get(&self, id: ResourceId) -> Result<&T, BackendError> {
        self.map.get(&id).ok_or(BackendError::MissingResource(id))
    }

    /// Buffer `id`, or [`BackendError::MissingResource`].
    pub fn get_mut(&mut self, id: ResourceId) -> Result<&mut T, BackendError> {
        self.map
            .get_mut(&id)
            .ok_or(BackendError::MissingResource(id))
    }

    /// Whether buffer `id` is held.
    pub fn contains(&self, id: ResourceId) -> bool {
        self.map.contains_key(&id)
    }

    /// Holds `buffer` as `id`; returns the one it replaces.
    pub fn insert(&mut self, id: ResourceId, buffer: T) -> Option<T> {
        self.map.insert(id, buffer)
    }

    /// Lets buffer `id` go (`Step::Free`, or before a replacement is made); returns it.
    pub fn remove(&mut self, id: ResourceId) -> Option<T> {
        self.map.remove(&id)
    }

    /// How many buffers are held.
    pub fn len(&self) -> usize {
        self.map.len()
    }

    /// Whether no buffer is held.
    pub fn is_empty(&self) -> bool {
        self.map.is_empty()
    }

    /// Lets every buffer go.
    pub fn clear(&mut self) {
        self.map.clear();
    }
}

/// The bounds check of a `Step::Write` (`label`'s `data_len` bytes at byte `offset`)
/// into a buffer of `buffer_len` bytes, made by every backend before it copies.
pub fn check_write(
    label: &str,
    buffer_len: u64,
    offset: u64,
    data_len: usize,
) -> Result<(), BackendError> {
    let end = offset.checked_add(data_len as u64);
    if end.is_none_or(|e| e > buffer_len) {
        return Err(BackendError::BadArgument(format!(
            "{label}: write of {data_len} bytes at {offset} into a buffer of {buffer_len}"
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_must_lie_inside_the_buffer() {
        assert!(check_write("w", 16, 8, 8).is_ok());
        assert!(check_write("w", 16, 16, 0).is_ok());
        let e = check_write("tlas", 16, 12, 8).unwrap_err();
        assert_eq!(
            e.to_string(),
            "bad argument: tlas: write of 8 bytes at 12 into a buffer of 16"
        );
        // an offset near u64::MAX does not wrap around
        assert!(check_write("w", 16, u64::MAX - 2, 8).is_err());
    }

    #[test]
    fn a_missing_buffer_is_a_typed_error() {
        let mut t: ResourceTable<u32> = ResourceTable::default();
        let id = ResourceId(7);
        assert!(matches!(t.get(id), Err(BackendError::MissingResource(i)) if i == id));
        t.insert(id, 3);
        assert_eq!(t.get(id).copied().ok(), Some(3));
        assert_eq!(t.remove(id), Some(3));
        assert!(!t.contains(id));
    }
}
