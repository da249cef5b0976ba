//! Crafted lengths must fail fast without allocating more than the file
//! justifies. A counting allocator records the largest single allocation.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use mesh_core::artifact::{read_artifact, read_header, Header};
use sha2::{Digest, Sha256};

struct Counting;
static LARGEST: AtomicUsize = AtomicUsize::new(0);
/// Bytes currently allocated, and the most allocated at once since the last reset.
static CURRENT: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

fn grow(by: usize) {
    let now = CURRENT.fetch_add(by, Ordering::Relaxed) + by;
    PEAK.fetch_max(now, Ordering::Relaxed);
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        LARGEST.fetch_max(layout.size(), Ordering::Relaxed);
        grow(layout.size());
        System.alloc(layout)
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        LARGEST.fetch_max(layout.size(), Ordering::Relaxed);
        grow(layout.size());
        System.alloc_zeroed(layout)
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        LARGEST.fetch_max(new_size, Ordering::Relaxed);
        // Counted as a fresh allocation before the old one is released (the
        // worst case, a moving realloc).
        grow(new_size);
        CURRENT.fetch_sub(layout.size(), Ordering::Relaxed);
        System.realloc(ptr, layout, new_size)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        CURRENT.fetch_sub(layout.size(), Ordering::Relaxed);
        System.dealloc(ptr, layout)
    }
}

#[global_allocator]
static ALLOC: Counting = Counting;

/// Tests in this file measure the process-wide largest allocation: run them one at a time.
static SERIAL: Mutex<()> = Mutex::new(());

/// Container bytes with the given raw header length field and payload, checksum valid.
fn container(header_len_field: u64, header: &[u8], payload: &[u8]) -> Vec<u8> {
    let mut b = Vec::new();
    b.extend_from_slice(b"SURFCAP\0");
    b.extend_from_slice(&1u32.to_le_bytes());
    b.extend_from_slice(&4u32.to_le_bytes());
    b.extend_from_slice(b"test");
    b.extend_from_slice(&1u32.to_le_bytes());
    b.extend_from_slice(&header_len_field.to_le_bytes());
    b.extend_from_slice(header);
    b.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    b.extend_from_slice(payload);
    let d = Sha256::digest(&b);
    b.extend_from_slice(&d);
    b
}

fn largest_allocation_during<T>(f: impl FnOnce() -> T) -> (T, usize) {
    LARGEST.store(0, Ordering::Relaxed);
    let r = f();
    (r, LARGEST.load(Ordering::Relaxed))
}

#[test]
fn header_length_of_2_pow_60_fails_fast_without_allocating() {
    let _g = SERIAL.lock().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("crafted.art");
    let bytes = container(1 << 60, b"{}", b"");
    std::fs::write(&path, &bytes).unwrap();
    let t = std::time::Instant::now();
    let (r, largest) = largest_allocation_during(|| read_header(&path));
    let msg = r.unwrap_err().to_string();
    assert!(
        msg.contains("truncated") && msg.contains(&(1u64 << 60).to_string()),
        "{msg}"
    );
    assert!(
        largest < 64 * 1024,
        "allocated {largest} bytes for a {}-byte file",
        bytes.len()
    );
    assert!(t.elapsed().as_secs() < 5);
}

#[test]
fn crafted_string_length_inside_a_valid_payload_is_bounded() {
    let _g = SERIAL.lock().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("crafted.art");
    // bincode varint: 253 marks a u64 length; claim a 2^40-byte string.
    let mut payload = vec![253u8];
    payload.extend_from_slice(&(1u64 << 40).to_le_bytes());
    payload.extend_from_slice(b"abc");
    let header = serde_json::to_vec(&Header::default()).unwrap();
    std::fs::write(&path, container(header.len() as u64, &header, &payload)).unwrap();
    let (r, largest) = largest_allocation_during(|| read_artifact::<String>(&path, "test", 1));
    let msg = r.unwrap_err().to_string();
    assert!(msg.contains("payload does not decode"), "{msg}");
    assert!(largest < 64 * 1024, "allocated {largest} bytes");
}

#[test]
fn crafted_sequence_length_inside_a_valid_payload_is_bounded() {
    let _g = SERIAL.lock().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("crafted.art");
    let mut payload = vec![253u8];
    payload.extend_from_slice(&(1u64 << 60).to_le_bytes());
    payload.extend_from_slice(&1.5f64.to_le_bytes());
    let header = serde_json::to_vec(&Header::default()).unwrap();
    std::fs::write(&path, container(header.len() as u64, &header, &payload)).unwrap();
    let (r, largest) = largest_allocation_during(|| read_artifact::<Vec<f64>>(&path, "test", 1));
    assert!(r
        .unwrap_err()
        .to_string()
        .contains("payload does not decode"));
    // serde's sequence visitor caps its up-front reservation at 1 MiB.
    assert!(largest <= 1 << 20, "allocated {largest} bytes");
}

/// FORMATS.md's memory bound: a payload of `p` bytes decodes into at most
/// `DECODE_EXPANSION * p` bytes of values (bincode's accounting), and vector
/// growth at most doubles that transiently. The worst legal payload for
/// the expansion is a long list of empty lists (1 byte on disk, 24 in memory).
#[test]
fn peak_memory_of_a_payload_of_empty_lists_is_within_the_documented_bound() {
    use mesh_core::artifact::DECODE_EXPANSION;
    let _g = SERIAL.lock().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("lists.art");
    let n: u32 = 1_000_000;
    let mut payload = vec![252u8];
    payload.extend_from_slice(&n.to_le_bytes());
    payload.extend(std::iter::repeat_n(0u8, n as usize));
    let header = serde_json::to_vec(&Header::default()).unwrap();
    std::fs::write(&path, container(header.len() as u64, &header, &payload)).unwrap();
    let file_len = std::fs::metadata(&path).unwrap().len() as usize;
    let base = CURRENT.load(Ordering::Relaxed);
    PEAK.store(base, Ordering::Relaxed);
    let (_, v): (Header, Vec<Vec<u32>>) = read_artifact(&path, "test", 1).unwrap();
    let peak = PEAK.load(Ordering::Relaxed) - base;
    assert_eq!(v.len(), n as usize);
    // The file's bytes are held while decoding: count them apart.
    let decode_peak = peak - file_len;
    eprintln!("{} empty lists ({} payload bytes): decode peak {decode_peak} bytes", n, payload.len());
    assert!(
        decode_peak <= 2 * DECODE_EXPANSION * payload.len(),
        "peak {decode_peak} bytes for a {}-byte payload",
        payload.len()
    );
    // And the bound is not loose by more than a small factor: 24 bytes per list.
    assert!(decode_peak >= 24 * n as usize, "{decode_peak}");
}

/// A valid binary PLY of `faces` 255-gons over `vertices` vertices: the densest triangle count a
/// PLY byte can carry (1,021 bytes per polygon, 253 fan triangles).
fn polygon_ply(vertices: u32, faces: u32) -> Vec<u8> {
    let mut b = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {vertices}\nproperty float x\nproperty float y\n\
         property float z\nelement face {faces}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    .into_bytes();
    for v in 0..vertices {
        for c in [v as f32, (v % 7) as f32, (v % 13) as f32] {
            b.extend_from_slice(&c.to_le_bytes());
        }
    }
    for f in 0..faces {
        b.push(255);
        for k in 0..255u32 {
            // Distinct corners, spread so that the fans share few edges (the most edges per byte).
            let v = (f.wrapping_mul(7919) + k * (1 + f % 97)) % vertices;
            b.extend_from_slice(&(v as i32).to_le_bytes());
        }
    }
    b
}

#[test]
fn peak_memory_of_a_polygon_ply_and_its_topology_is_within_the_documented_bound() {
    use mesh_core::io::ply::parse_ply;
    use mesh_core::topology::Topology;
    let _g = SERIAL.lock().unwrap();
    let bytes = polygon_ply(30_000, 2_000);
    let base = CURRENT.load(Ordering::Relaxed);
    PEAK.store(base, Ordering::Relaxed);
    let mesh = parse_ply(&bytes).unwrap();
    let topology = Topology::new(mesh.vertices.len(), &mesh.faces);
    let peak = PEAK.load(Ordering::Relaxed) - base;
    assert_eq!(topology.n_faces(), 2_000 * 253);
    eprintln!(
        "{}-byte PLY of 255-gons: {} triangles, {} edges, peak {peak} bytes ({:.1} x the file)",
        bytes.len(),
        topology.n_faces(),
        topology.n_edges(),
        peak as f64 / bytes.len() as f64
    );
    // docs/FORMATS.md, "Memory": reading a mesh and building its adjacency peaks below 32 x the
    // file's size (about 120 bytes per triangle; a 255-gon packs 253 triangles in 1,021 bytes).
    assert!(peak <= 32 * bytes.len(), "peak {peak} bytes for a {}-byte file", bytes.len());
}
