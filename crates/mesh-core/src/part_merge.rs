//! Per-part artifacts and their join into the whole model (`merge-parts`).
//!
//! `pca-fit`, `gpr-train` and `gpdm-train` fit their parts independently, so one cluster task
//! can fit one part: with `--part NAME` a stage fits only that part and writes a *piece*, an
//! artifact of kind `<kind>-part` (e.g. `pca-model-part`) whose payload is a [`Piece`]: the
//! names of every part of the whole model in its order, the piece's own part, and what the
//! whole model holds for that part (the kind's [`Partitioned::Body`]). The piece's header is
//! the header the whole run writes, with `"part": NAME` added to its params ([`PART_PARAM`]).
//!
//! [`merge`] reads the pieces of one model and checks that
//! * their headers agree but for the part and the output path (same producer, params, seed and
//!   inputs),
//! * they name the same part list, and each of its parts is in exactly one piece;
//!
//! then joins the bodies in the part order ([`Partitioned::join`]) and writes the whole model
//! under the pieces' header without the part, with the merge's output path as `out` and the
//! merge's report path (or none) as `report`: the header of the single-process run that wrote
//! to those paths. Kinds whose stage writes a JSON report of its parts ([`PartReports`]) join
//! the pieces' reports too ([`merge_reporting`]), into the report the whole run writes.
//! A part fitted alone is computed exactly as in the whole run, so the merged file is
//! byte-identical to the whole run's.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::artifact::{Artifact, Header};
use crate::{Error, Result};

/// The params key naming a piece's part (the stages' `--part`).
pub const PART_PARAM: &str = "part";
/// The params key of the output path (the stages' `--out`): each piece has its own, the merged
/// model records the one `merge` writes to.
pub const OUT_PARAM: &str = "out";
/// The params key of the report path (the stages' `--report`): each piece has its own, the
/// merged model records the one `merge_reporting` writes (none after [`merge`]).
pub const REPORT_PARAM: &str = "report";

/// A model kind whose parts are fitted independently and can be written one per piece.
pub trait Partitioned: Artifact {
    /// Kind of the piece artifacts: the model's kind followed by `-part`.
    const PIECE_KIND: &'static str;
    /// What the whole model holds for one part.
    type Body: Serialize + DeserializeOwned;
    /// Checks a decoded body as [`Artifact::validate`] checks the whole model (the error is the
    /// problem, without the file name).
    fn validate_body(body: &Self::Body) -> std::result::Result<(), String>;
    /// Joins `bodies`, one per name of `parts` in that order, into the whole model (the error
    /// is the problem, e.g. two pieces disagreeing on a shared field).
    fn join(parts: &[String], bodies: Vec<Self::Body>) -> std::result::Result<Self, String>;
}

/// A [`Partitioned`] kind whose stage also writes a JSON report of the parts it fits
/// (`--report`); a piece's report describes its one part.
pub trait PartReports: Partitioned {
    type Report: Serialize + DeserializeOwned;
    /// The part a piece's report describes (the error: it is not the report of one part).
    fn report_part(report: &Self::Report) -> std::result::Result<String, String>;
    /// Joins the reports of every part, given in the model's part order, into the whole run's.
    fn join_reports(reports: Vec<Self::Report>) -> std::result::Result<Self::Report, String>;
    /// The report file's text, exactly as the stage writes it.
    fn report_text(report: &Self::Report) -> serde_json::Result<String>;
}

/// The payload of a piece: one part of a [`Partitioned`] model.
#[derive(Serialize, Deserialize)]
#[serde(bound = "")]
pub struct Piece<M: Partitioned> {
    /// Every part of the whole model, in its order.
    pub parts: Vec<String>,
    /// The part this piece holds (one of `parts`).
    pub part: String,
    pub body: M::Body,
}

impl<M: Partitioned> Artifact for Piece<M> {
    const KIND: &'static str = M::PIECE_KIND;
    const VERSION: u32 = M::VERSION;

    /// Unique part names, the piece's part among them, a valid body.
    fn validate(&self) -> std::result::Result<(), String> {
        if let Some((k, name)) = self.parts.iter().enumerate().find(|(k, n)| self.parts[..*k].contains(n)) {
            return Err(format!("part {k} ('{name}') appears twice in the part list"));
        }
        if !self.parts.contains(&self.part) {
            return Err(format!("part '{}' is not in its part list ({})", self.part, self.parts.join(", ")));
        }
        M::validate_body(&self.body).map_err(|e| format!("part '{}': {e}", self.part))
    }
}

/// Index of part `name` among `known`, the parts `source` defines; otherwise a one-line error
/// naming `source` and listing the known parts.
pub fn select(known: &[String], name: &str, source: &Path) -> Result<usize> {
    known.iter().position(|k| k == name).ok_or_else(|| {
        Error::file(source, format!("no part '{name}' (its parts: {})", known.join(", ")))
    })
}

/// Writes the piece of part `parts[k]` to `out`: `header` (the whole run's) with the part added
/// to its params.
pub fn save_piece<M: Partitioned>(
    out: &Path,
    header: &Header,
    parts: &[String],
    k: usize,
    body: M::Body,
) -> Result<()> {
    let mut header = header.clone();
    let name = parts
        .get(k)
        .ok_or_else(|| Error::invalid(format!("part index {k} of {} parts", parts.len())))?;
    match header.params.as_object_mut() {
        Some(map) => {
            map.insert(PART_PARAM.to_string(), name.clone().into());
        }
        None => return Err(Error::invalid("a piece's header needs params to record its part in")),
    }
    Piece::<M> {
        parts: parts.to_vec(),
        part: name.clone(),
        body,
    }
    .save(out, &header)
}

/// The header of the whole model written to `out` (and its report to `report`) that a piece
/// belongs to: its own without the part, with `out` as the params' output path ([`OUT_PARAM`])
/// and `report` as their report path ([`REPORT_PARAM`]) when they record them.
fn whole_header(path: &Path, header: &Header, out: &Path, report: Option<&Path>) -> Result<Header> {
    let mut whole = header.clone();
    let Some(map) = whole.params.as_object_mut() else {
        return Err(Error::file(path, "header records no params: not a piece written with --part"));
    };
    match map.remove(PART_PARAM) {
        Some(serde_json::Value::String(_)) => {}
        _ => return Err(Error::file(path, format!("header params record no '{PART_PARAM}': not a piece written with --part"))),
    }
    if let Some(o) = map.get_mut(OUT_PARAM) {
        *o = serde_json::to_value(out).map_err(|e| Error::invalid(format!("output path: {e}")))?;
    }
    if let Some(r) = map.get_mut(REPORT_PARAM) {
        *r = serde_json::to_value(report).map_err(|e| Error::invalid(format!("report path: {e}")))?;
    }
    Ok(whole)
}

/// What differs between two headers of pieces (`None`: nothing), for the error message.
fn header_difference(a: &Header, b: &Header) -> Option<String> {
    if a.producer != b.producer {
        return Some(format!("written by {} {}, not {} {}", b.producer.stage, b.producer.version, a.producer.stage, a.producer.version));
    }
    if a.params != b.params {
        let (Some(pa), Some(pb)) = (a.params.as_object(), b.params.as_object()) else {
            return Some("other parameters".to_string());
        };
        let keys: std::collections::BTreeSet<&String> = pa.keys().chain(pb.keys()).collect();
        let differing: Vec<&str> = keys.into_iter().filter(|k| pa.get(*k) != pb.get(*k)).map(|k| k.as_str()).collect();
        return Some(format!("other parameters ({})", differing.join(", ")));
    }
    if a.seed != b.seed {
        return Some(format!("seed {:?}, not {:?}", b.seed, a.seed));
    }
    if a.command_line != b.command_line {
        return Some("another command line".to_string());
    }
    if a.inputs != b.inputs {
        let first = a.inputs.iter().zip(&b.inputs).find(|(x, y)| x != y);
        return Some(match first {
            Some((x, y)) if x.path != y.path => format!("other inputs ('{}', not '{}')", y.path, x.path),
            Some((x, _)) => format!("other inputs ('{}' has other contents)", x.path),
            None => format!("{} inputs, not {}", b.inputs.len(), a.inputs.len()),
        });
    }
    None
}

/// Joins the pieces in `inputs` (any order) into the whole model and writes it to `out`
/// (atomically), checking what the module documentation lists; each failure is one line
/// naming the offending file.
pub fn merge<M: Partitioned>(inputs: &[PathBuf], out: &Path) -> Result<()> {
    let (header, model, _) = join_pieces::<M>(inputs, out, None)?;
    model.save(out, &header)
}

/// [`merge`], and the pieces' reports in `reports` (any order, one per part) joined into the
/// whole run's report at `report`. Nothing is written unless both joins succeed; the report
/// is written first, so the model's presence says both are complete.
pub fn merge_reporting<M: PartReports>(inputs: &[PathBuf], out: &Path, reports: &[PathBuf], report: &Path) -> Result<()> {
    let (header, model, parts) = join_pieces::<M>(inputs, out, Some(report))?;
    let text = join_report_files::<M>(&parts, reports)?;
    crate::atomic::write_bytes_atomic(report, text.as_bytes())?;
    model.save(out, &header)
}

/// The text of the whole run's report from the pieces' reports of the model's `parts`.
fn join_report_files<M: PartReports>(parts: &[String], paths: &[PathBuf]) -> Result<String> {
    let mut by_part: BTreeMap<usize, (&PathBuf, M::Report)> = BTreeMap::new();
    for path in paths {
        let bytes = crate::input::read_regular_file(path)?;
        let report: M::Report = serde_json::from_slice(&bytes).map_err(|e| Error::file(path, format!("not a report of {}: {e}", M::PIECE_KIND)))?;
        let part = M::report_part(&report).map_err(|e| Error::file(path, e))?;
        let k = parts.iter().position(|p| *p == part).ok_or_else(|| {
            Error::file(path, format!("a report of part '{part}', not one of the model's ({})", parts.join(", ")))
        })?;
        if let Some((other, _)) = by_part.get(&k) {
            return Err(Error::file(path, format!("the report of part '{part}' is already {}", other.display())));
        }
        by_part.insert(k, (path, report));
    }
    let missing: Vec<&str> = (0..parts.len()).filter(|k| !by_part.contains_key(k)).map(|k| parts[k].as_str()).collect();
    if !missing.is_empty() {
        return Err(Error::invalid(format!("no report for part{} {} of the {} parts", if missing.len() > 1 { "s" } else { "" }, missing.join(", "), parts.len())));
    }
    let first = by_part.values().next().map(|(p, _)| (*p).clone()).unwrap_or_default();
    let joined = M::join_reports(by_part.into_values().map(|(_, r)| r).collect())
        .map_err(|e| Error::file(&first, format!("cannot join the reports: {e}")))?;
    M::report_text(&joined).map_err(|e| Error::invalid(format!("cannot write the joined report: {e}")))
}

/// The whole model's header, the joined model and its part names, from the pieces in `inputs`.
fn join_pieces<M: Partitioned>(inputs: &[PathBuf], out: &Path, report: Option<&Path>) -> Result<(Header, M, Vec<String>)> {
    let (first_path, rest) = inputs
        .split_first()
        .ok_or_else(|| Error::invalid("no pieces to merge"))?;
    let (first_header, first) = Piece::<M>::load_with_header(first_path)?;
    let header = whole_header(first_path, &first_header, out, report)?;
    let parts = first.parts.clone();
    let mut bodies: BTreeMap<usize, (PathBuf, M::Body)> = BTreeMap::new();
    let mut add = |path: &Path, piece: Piece<M>| -> Result<()> {
        let k = parts.iter().position(|p| *p == piece.part).expect("validated: part in its list");
        if let Some((other, _)) = bodies.get(&k) {
            return Err(Error::file(path, format!("part '{}' is already in {}", piece.part, other.display())));
        }
        bodies.insert(k, (path.to_path_buf(), piece.body));
        Ok(())
    };
    add(first_path, first)?;
    for path in rest {
        let (h, piece) = Piece::<M>::load_with_header(path)?;
        let h = whole_header(path, &h, out, report)?;
        if let Some(diff) = header_difference(&header, &h) {
            return Err(Error::file(
                path,
                format!("not a piece of the same model as {}: {diff}", first_path.display()),
            ));
        }
        if piece.parts != parts {
            return Err(Error::file(
                path,
                format!(
                    "a piece of a model of parts ({}), {} is of ({})",
                    piece.parts.join(", "),
                    first_path.display(),
                    parts.join(", ")
                ),
            ));
        }
        add(path, piece)?;
    }
    let missing: Vec<&str> = (0..parts.len())
        .filter(|k| !bodies.contains_key(k))
        .map(|k| parts[k].as_str())
        .collect();
    if !missing.is_empty() {
        return Err(Error::invalid(format!(
            "no piece for part{} {} of the {} parts ({})",
            if missing.len() > 1 { "s" } else { "" },
            missing.join(", "),
            parts.len(),
            parts.join(", ")
        )));
    }
    let bodies: Vec<M::Body> = bodies.into_values().map(|(_, b)| b).collect();
    let model = M::join(&parts, bodies).map_err(|e| Error::file(first_path, format!("cannot join the pieces: {e}")))?;
    model
        .validate()
        .map_err(|e| Error::file(first_path, format!("the joined '{}' is invalid: {e}", M::KIND)))?;
    Ok((header, model, parts))
}
