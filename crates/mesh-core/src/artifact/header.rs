//! The provenance header of an artifact: which stage wrote it, its command line or parameters,
//! its seed and its input files with their SHA-256.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::hash::sha256_file;
use crate::error::{Error, Result};

/// Which stage wrote an artifact.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Producer {
    /// Stage (binary) name, e.g. `"align"`.
    pub stage: String,
    /// Version of the crate that holds the stage, e.g. `"0.1.0"`.
    pub version: String,
}

/// One input file of a stage and the SHA-256 of its bytes (lowercase hex).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct InputRecord {
    pub path: String,
    pub sha256: String,
}

/// Provenance header of an artifact, stored as JSON.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Header {
    pub producer: Producer,
    /// The stage's command line, for stages that record no params; the program name is
    /// reduced to its file name so the record does not depend on where the binary was built.
    pub command_line: Vec<String>,
    /// The stage's parameters (its parsed options), any JSON value.
    pub params: serde_json::Value,
    /// Random seed, for stages that use randomness.
    pub seed: Option<u64>,
    /// Input files and their hashes.
    pub inputs: Vec<InputRecord>,
}

impl Header {
    /// A header for `stage` of crate version `version` (pass
    /// `env!("CARGO_PKG_VERSION")`), with no command line, params, seed or inputs.
    pub fn new(stage: &str, version: &str) -> Self {
        Header {
            producer: Producer {
                stage: stage.to_string(),
                version: version.to_string(),
            },
            command_line: Vec::new(),
            params: serde_json::Value::Null,
            seed: None,
            inputs: Vec::new(),
        }
    }

    /// Records the given command line (argument 0 reduced to its file name).
    pub fn with_command_line<I, S>(mut self, args: I) -> Self
    where
        I: IntoIterator<Item = S>,
        S: Into<String>,
    {
        self.command_line = args.into_iter().map(Into::into).collect();
        if let Some(first) = self.command_line.first_mut() {
            if let Some(name) = Path::new(first.as_str()).file_name() {
                *first = name.to_string_lossy().into_owned();
            }
        }
        self
    }

    /// Records this process's command line ([`std::env::args_os`], lossily UTF-8).
    pub fn with_process_command_line(self) -> Self {
        let args: Vec<String> = std::env::args_os()
            .map(|a| a.to_string_lossy().into_owned())
            .collect();
        self.with_command_line(args)
    }

    /// Records the stage parameters (anything serde can turn into JSON) and drops the
    /// command line: the parsed parameters describe the run completely, while the command
    /// line also holds flags that change no output (`-v`, `--threads`), so a header with
    /// params is the same bytes however the stage was invoked.
    pub fn with_params<P: Serialize>(mut self, params: &P) -> Result<Self> {
        self.params = serde_json::to_value(params)
            .map_err(|e| Error::invalid(format!("cannot record parameters as JSON: {e}")))?;
        self.command_line.clear();
        Ok(self)
    }

    pub fn with_seed(mut self, seed: u64) -> Self {
        self.seed = Some(seed);
        self
    }

    /// Records `path` (as given) as an input whose SHA-256 is `sha256`, from a read that hashed
    /// it on the way (e.g. [`Artifact::load_hashed`](super::Artifact::load_hashed)).
    pub fn with_input_hashed(mut self, path: impl AsRef<Path>, sha256: String) -> Self {
        self.inputs.push(InputRecord { path: path.as_ref().display().to_string(), sha256 });
        self
    }

    /// Hashes `path` and records it as an input (path as given).
    pub fn with_input(mut self, path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let sha256 = sha256_file(path)?;
        self.inputs.push(InputRecord {
            path: path.display().to_string(),
            sha256,
        });
        Ok(self)
    }
}
