//! The object tree, walked depth-first without recursion down to the PolyMesh sought: node
//! paths, names matched by name or full path, and the Xforms above a node.

use std::collections::HashSet;

use super::archive::{Archive, Schema};
use crate::input::escape_control;
use crate::io::ogawa::Group;

/// Object trees deeper than this are refused (real scenes are a few levels deep).
pub(super) const MAX_DEPTH: usize = 1000;

/// An object of the tree walked so far.
pub(super) struct Node<'a> {
    pub(super) name: String,
    pub(super) group: Group<'a>,
    pub(super) parent: Option<usize>,
    pub(super) depth: usize,
    pub(super) is_xform: bool,
    /// The object `--object` names, or one below it (every object when none is named).
    pub(super) chosen: bool,
}

/// The object tree walked down to the PolyMesh sought.
pub(super) struct Tree<'a> {
    pub(super) nodes: Vec<Node<'a>>,
}

impl Tree<'_> {
    /// The full path of node `i` (`/Cube/CubeShape`).
    pub(super) fn path(&self, i: usize) -> String {
        let mut names = Vec::new();
        let mut at = Some(i);
        while let Some(n) = at {
            names.push(self.nodes[n].name.as_str());
            at = self.nodes[n].parent;
        }
        names.iter().rev().fold(String::new(), |p, n| p + "/" + n)
    }

    /// Whether node `i` is the object `wanted`: its name, or its full path when `wanted`
    /// starts with `/` (compared upwards, without building the path).
    pub(super) fn is(&self, i: usize, wanted: &str) -> bool {
        let Some(path) = wanted.strip_prefix('/') else {
            return self.nodes[i].name == wanted;
        };
        let mut at = Some(i);
        for part in path.rsplit('/') {
            match at {
                Some(n) if self.nodes[n].name == part => at = self.nodes[n].parent,
                _ => return false,
            }
        }
        at.is_none()
    }

    /// The Xform ancestors of node `i`, outermost first.
    pub(super) fn xforms(&self, i: usize) -> Vec<usize> {
        let mut out = Vec::new();
        let mut at = self.nodes[i].parent;
        while let Some(n) = at {
            if self.nodes[n].is_xform {
                out.push(n);
            }
            at = self.nodes[n].parent;
        }
        out.reverse();
        out
    }
}

/// The first PolyMesh (depth-first) that `wanted` names (by name or full path) or that lies
/// below the object it names (Maya's transform `body` above `bodyShape`), else the first,
/// with the tree walked to reach it; also the paths of (up to 10) other PolyMeshes seen, for the
/// error when none matches.
pub(super) fn find_polymesh<'a>(
    archive: &mut Archive<'a>,
    wanted: Option<&str>,
) -> std::result::Result<(Tree<'a>, Option<usize>, Vec<String>), String> {
    let mut seen_groups = HashSet::new();
    let mut tree = Tree { nodes: Vec::new() };
    let mut others = Vec::new();
    // Depth-first with an explicit stack: a crafted tree cannot exhaust the call stack.
    let mut stack: Vec<(Option<usize>, Group<'a>)> = vec![(None, archive.top)];
    while let Some((node, group)) = stack.pop() {
        let where_ = |tree: &Tree| escape_control(&node.map_or("/".to_string(), |n| tree.path(n))).into_owned();
        if group.offset() != 0 && !seen_groups.insert(group.offset()) {
            return Err(format!("object {}: its group is reached twice (a cycle in the object tree)", where_(&tree)));
        }
        let depth = node.map_or(0, |n| tree.nodes[n].depth + 1);
        if depth > MAX_DEPTH {
            return Err(format!("the object tree is deeper than {MAX_DEPTH} levels"));
        }
        let headers = archive.object_headers(&group).map_err(|e| format!("object {}: {e}", where_(&tree)))?;
        let mut children = Vec::with_capacity(headers.len());
        for (i, (name, schema)) in headers.into_iter().enumerate() {
            let child = group
                .group(i as u64 + 1)
                .map_err(|e| format!("object {}/{}: {e}", where_(&tree), escape_control(&name)))?;
            let parent_chosen = node.is_some_and(|n| tree.nodes[n].chosen);
            tree.nodes.push(Node {
                name,
                group: child,
                parent: node,
                depth,
                is_xform: schema == Schema::Xform,
                chosen: false,
            });
            let id = tree.nodes.len() - 1;
            let chosen = wanted.is_none_or(|w| parent_chosen || tree.is(id, w));
            tree.nodes[id].chosen = chosen;
            if schema == Schema::PolyMesh {
                if chosen {
                    return Ok((tree, Some(id), others));
                }
                if others.len() < 10 {
                    others.push(tree.path(id));
                }
            }
            children.push((Some(id), child));
        }
        stack.extend(children.into_iter().rev());
    }
    Ok((tree, None, others))
}
