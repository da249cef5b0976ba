//! Ordered one-rings (vertex fans), which `mesh_core::topology` does not provide.

use crate::{Error, Result};
use std::collections::{HashMap, HashSet};

/// The one-ring of `v` in counter-clockwise order (following the face orientation).
/// For a boundary vertex the fan is open and starts at the boundary neighbour that has
/// no predecessor. `incident` lists the faces around `v`.
pub(crate) fn ordered_fan(v: usize, incident: &[u32], faces: &[[u32; 3]]) -> Result<Vec<usize>> {
    let mut succ: HashMap<usize, usize> = HashMap::new();
    let mut has_pred: HashSet<usize> = HashSet::new();
    for &f in incident {
        let face = faces[f as usize];
        let k = face
            .iter()
            .position(|&x| x as usize == v)
            .expect("incident face");
        let a = face[(k + 1) % 3] as usize;
        let b = face[(k + 2) % 3] as usize;
        if succ.insert(a, b).is_some() || !has_pred.insert(b) {
            return Err(Error::invalid(format!(
                "non-manifold or inconsistently oriented fan at vertex {v}"
            )));
        }
    }
    let mut start = *succ
        .keys()
        .min()
        .ok_or_else(|| Error::invalid(format!("vertex {v} has no faces")))?;
    let mut open = false;
    let mut keys: Vec<usize> = succ.keys().copied().collect();
    keys.sort_unstable();
    for a in keys {
        if !has_pred.contains(&a) {
            start = a;
            open = true;
            break;
        }
    }
    let mut fan = vec![start];
    let mut cur = start;
    while let Some(&nx) = succ.get(&cur) {
        if nx == start {
            break;
        }
        fan.push(nx);
        cur = nx;
        if fan.len() > incident.len() + 1 {
            return Err(Error::invalid(format!("non-manifold fan at vertex {v}")));
        }
    }
    let expected = if open {
        incident.len() + 1
    } else {
        incident.len()
    };
    if fan.len() != expected {
        return Err(Error::invalid(format!("non-manifold fan at vertex {v}")));
    }
    Ok(fan)
}
