//! Loading of the TOML model files (agents and affordance hierarchies), with errors
//! that name the file, the line and the key.

use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;

/// What went wrong loading a model file (agent or hierarchy). Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    /// The file could not be read.
    #[error("{path}: cannot read: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// The TOML is malformed or a key is unknown, missing or of the wrong type.
    #[error("{path}:{line}: {what}")]
    Syntax {
        /// The file.
        path: PathBuf,
        /// 1-based line of the problem (0 when unknown).
        line: usize,
        /// What is wrong, with the key.
        what: String,
    },
    /// A model named on the command line is neither a file, a folder nor a built-in one.
    #[error("{name}: {what}")]
    Unknown {
        /// The name as given.
        name: String,
        /// What is wrong.
        what: String,
    },
    /// The file parses but describes an impossible model.
    #[error("{path}: {key}: {what}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// The key (for example `joint.knee_l.parent`).
        key: String,
        /// What is wrong.
        what: String,
    },
}

/// Reads and deserialises a TOML model file, mapping parse errors to file and line.
pub fn read_toml<T: DeserializeOwned>(path: &Path) -> Result<T, ModelError> {
    let text = std::fs::read_to_string(path).map_err(|source| ModelError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_toml(&text, path)
}

/// Deserialises TOML text; `path` only names the source in errors.
pub fn parse_toml<T: DeserializeOwned>(text: &str, path: &Path) -> Result<T, ModelError> {
    toml::from_str(text).map_err(|e| {
        let line = e
            .span()
            .map(|s| text[..s.start.min(text.len())].matches('\n').count() + 1)
            .unwrap_or(0);
        ModelError::Syntax {
            path: path.to_path_buf(),
            line,
            what: e.message().trim().to_string(),
        }
    })
}

/// Builds an [`ModelError::Invalid`] for `path`.
pub(crate) fn invalid(path: &Path, key: impl Into<String>, what: impl Into<String>) -> ModelError {
    ModelError::Invalid {
        path: path.to_path_buf(),
        key: key.into(),
        what: what.into(),
    }
}
