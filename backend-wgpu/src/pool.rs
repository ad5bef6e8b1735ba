//! Per-submission resources kept and reused: timestamp query sets with
//! their resolve buffers, and mappable staging buffers by size. A submission takes what it
//! needs when it is encoded and gives it back when it is collected (the staging unmapped),
//! so a frame loop in its steady state creates neither.

use std::collections::HashMap;

/// A timestamp query set for up to `capacity` kernels (two queries each) and the buffer
/// its ticks are resolved into.
pub struct TimestampQueries {
    pub set: wgpu::QuerySet,
    pub resolve: wgpu::Buffer,
    pub capacity: u32,
}

/// The free resources.
#[derive(Default)]
pub struct SubmissionPool {
    queries: Vec<TimestampQueries>,
    staging: HashMap<u64, Vec<wgpu::Buffer>>,
    /// Query sets and staging buffers created so far (what the pool saves shows here).
    pub created: u64,
}

/// Most free staging buffers kept per size (a frame's readbacks times the frames in
/// flight; beyond that they are dropped).
const MAX_FREE_PER_SIZE: usize = 8;

impl SubmissionPool {
    /// A query set for `kernels` kernels: the smallest free one that holds them, or a new
    /// one (capacity rounded up to a power of two, at least 16).
    pub fn queries(&mut self, device: &wgpu::Device, kernels: u32) -> TimestampQueries {
        let best = self
            .queries
            .iter()
            .enumerate()
            .filter(|(_, q)| q.capacity >= kernels)
            .min_by_key(|(_, q)| q.capacity)
            .map(|(i, _)| i);
        if let Some(i) = best {
            return self.queries.swap_remove(i);
        }
        self.created += 1;
        let capacity = kernels.next_power_of_two().max(16);
        TimestampQueries {
            set: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 2 * capacity,
            }),
            resolve: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp resolve"),
                size: 16 * capacity as u64,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            capacity,
        }
    }

    /// Gives a query set back.
    pub fn give_queries(&mut self, q: TimestampQueries) {
        self.queries.push(q);
    }

    /// A mappable staging buffer of `size` bytes (a multiple of the copy alignment).
    pub fn staging(&mut self, device: &wgpu::Device, size: u64) -> wgpu::Buffer {
        if let Some(b) = self.staging.get_mut(&size).and_then(Vec::pop) {
            return b;
        }
        self.created += 1;
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("submission readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    /// Gives an unmapped staging buffer back.
    pub fn give_staging(&mut self, b: wgpu::Buffer) {
        let free = self.staging.entry(b.size()).or_default();
        if free.len() < MAX_FREE_PER_SIZE {
            free.push(b);
        }
    }
}
