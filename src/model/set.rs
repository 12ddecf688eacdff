//! The models of a run: every body (an agent file scaled to each body height) paired with
//! every affordance hierarchy (section 3). The height map and the voxelised scene do not
//! depend on them, so one scene serves the whole set (see [`crate::detect::detect_all`]).
//!
//! Models are named on the command line by file, by folder (every `*.toml` in it, in name
//! order) or by the name of a built-in copy of the repository's `agents/` and
//! `affordances/` files, so the binary works from any directory.

use std::path::{Path, PathBuf};

use crate::model::agent::Agent;
use crate::model::hierarchy::Hierarchy;
use crate::model::ModelError;

/// The agent files compiled into the binary, by name (`agents/NAME.toml`).
pub const BUILTIN_AGENTS: &[(&str, &str)] = &[
    ("human", include_str!("../../agents/human.toml")),
    ("child", include_str!("../../agents/child.toml")),
];

/// The hierarchy files compiled into the binary, by name (`affordances/NAME.toml`); all
/// of them run when none is named.
pub const BUILTIN_HIERARCHIES: &[(&str, &str)] = &[
    ("sitting", include_str!("../../affordances/sitting.toml")),
    ("lying", include_str!("../../affordances/lying.toml")),
];

/// Where a model's TOML text comes from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Source {
    /// A copy compiled into the binary: its name and its text.
    Builtin(&'static str, &'static str),
    /// A file.
    File(PathBuf),
}

impl Source {
    /// How the source is named in errors and reports.
    pub fn label(&self, folder: &str) -> PathBuf {
        match self {
            Source::Builtin(name, _) => PathBuf::from(format!("(built-in) {folder}/{name}.toml")),
            Source::File(p) => p.clone(),
        }
    }
}

/// Resolves command-line model names: a file, a folder of `*.toml` files, or the name of a
/// built-in model. No names means `defaults` (the built-in names to use).
pub fn sources(
    names: &[String],
    builtins: &'static [(&'static str, &'static str)],
    defaults: &[&str],
) -> Result<Vec<Source>, ModelError> {
    let builtin = |name: &str| {
        builtins
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(n, t)| Source::Builtin(n, t))
    };
    if names.is_empty() {
        return Ok(defaults.iter().filter_map(|n| builtin(n)).collect());
    }
    let mut out = Vec::new();
    for name in names {
        let path = Path::new(name);
        if path.is_dir() {
            let mut files: Vec<PathBuf> = std::fs::read_dir(path)
                .map_err(|source| ModelError::Io {
                    path: path.to_path_buf(),
                    source,
                })?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.is_file() && p.extension().is_some_and(|e| e == "toml"))
                .collect();
            files.sort();
            if files.is_empty() {
                return Err(ModelError::Unknown {
                    name: name.clone(),
                    what: "the folder holds no .toml model".into(),
                });
            }
            out.extend(files.into_iter().map(Source::File));
        } else if path.exists() {
            out.push(Source::File(path.to_path_buf()));
        } else if let Some(s) = builtin(name) {
            out.push(s);
        } else {
            let known: Vec<&str> = builtins.iter().map(|(n, _)| *n).collect();
            return Err(ModelError::Unknown {
                name: name.clone(),
                what: format!(
                    "no such file or folder, nor a built-in model (built-in: {})",
                    known.join(", ")
                ),
            });
        }
    }
    Ok(out)
}

/// One run of the method: a body (an agent at one height) and one hierarchy resolved
/// against it.
#[derive(Debug, Clone)]
pub struct Model {
    /// The body.
    pub agent: Agent,
    /// The hierarchy.
    pub hierarchy: Hierarchy,
}

/// Loads an agent from a source, scaled to `height` metres.
pub fn load_agent(source: &Source, height: f64) -> Result<Agent, ModelError> {
    match source {
        Source::Builtin(_, text) => Agent::from_toml(text, &source.label("agents"), height),
        Source::File(p) => Agent::load(p, height),
    }
}

/// Loads a hierarchy from a source, resolved against `agent`.
pub fn load_hierarchy(source: &Source, agent: &Agent) -> Result<Hierarchy, ModelError> {
    match source {
        Source::Builtin(_, text) => Hierarchy::from_toml(text, &source.label("affordances"), agent),
        Source::File(p) => Hierarchy::load(p, agent),
    }
}

/// Every body (each agent at each height, in that order) with every hierarchy.
pub fn load_set(
    agents: &[Source],
    hierarchies: &[Source],
    heights: &[f64],
) -> Result<Vec<Model>, ModelError> {
    let mut out = Vec::new();
    for a in agents {
        for &height in heights {
            let agent = load_agent(a, height)?;
            for h in hierarchies {
                let hierarchy = load_hierarchy(h, &agent)?;
                out.push(Model {
                    agent: agent.clone(),
                    hierarchy,
                });
            }
        }
    }
    Ok(out)
}

/// The affordance ids of a set of models, each once, in the order first met.
pub fn ids(models: &[Model]) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for m in models {
        for id in m.hierarchy.ids() {
            if !out.iter().any(|o| o == id) {
                out.push(id.to_string());
            }
        }
    }
    out
}

/// The body height used when none is given, metres (an average adult).
pub const DEFAULT_HEIGHT: f64 = 1.75;

/// Which models a command runs: bodies (agents at heights) and hierarchies, each named by
/// file, folder or built-in name (see [`crate::model::set::sources`]).
#[derive(Debug, Clone, Default)]
pub struct ModelChoice {
    /// Agents; empty for the built-in `human`.
    pub agents: Vec<String>,
    /// Hierarchies; empty for every built-in one (`sitting`, `lying`).
    pub hierarchies: Vec<String>,
    /// Body heights, metres; empty for [`DEFAULT_HEIGHT`].
    pub heights: Vec<f64>,
}

impl ModelChoice {
    /// Resolves the agent and hierarchy names to their sources, with the defaults.
    pub fn sources(&self) -> Result<(Vec<Source>, Vec<Source>), ModelError> {
        let agents = sources(&self.agents, BUILTIN_AGENTS, &["human"])?;
        let names: Vec<&str> = BUILTIN_HIERARCHIES.iter().map(|(n, _)| *n).collect();
        let hierarchies = sources(&self.hierarchies, BUILTIN_HIERARCHIES, &names)?;
        Ok((agents, hierarchies))
    }

    /// The body heights, metres, with the default.
    pub fn heights(&self) -> Vec<f64> {
        if self.heights.is_empty() {
            vec![DEFAULT_HEIGHT]
        } else {
            self.heights.clone()
        }
    }

    /// Resolves the names and loads every body with every hierarchy.
    pub fn load(&self) -> Result<Vec<Model>, ModelError> {
        let (agents, hierarchies) = self.sources()?;
        load_set(&agents, &hierarchies, &self.heights())
    }
}

/// Loads the agent file scaled to `height` and the hierarchy file resolved against it.
pub fn load_models(
    agent: &Path,
    affordances: &Path,
    height: f64,
) -> Result<(Agent, Hierarchy), ModelError> {
    let a = Agent::load(agent, height)?;
    let h = Hierarchy::load(affordances, &a)?;
    Ok((a, h))
}

/// The agent model compiled into the binary (`agents/human.toml`).
pub const BUILTIN_AGENT: &str = BUILTIN_AGENTS[0].1;
/// The sitting hierarchy compiled into the binary (`affordances/sitting.toml`).
pub const BUILTIN_SITTING: &str = BUILTIN_HIERARCHIES[0].1;
/// The lying hierarchy compiled into the binary (`affordances/lying.toml`).
pub const BUILTIN_LYING: &str = BUILTIN_HIERARCHIES[1].1;

#[cfg(test)]
mod tests {
    use super::*;

    fn names(v: &[&str]) -> Vec<String> {
        v.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn no_names_give_every_default_builtin() {
        let s = sources(&[], BUILTIN_HIERARCHIES, &["sitting", "lying"]).unwrap();
        assert_eq!(s.len(), 2);
        assert!(matches!(s[1], Source::Builtin("lying", _)));
    }

    #[test]
    fn builtin_names_and_unknown_names() {
        let s = sources(&names(&["lying"]), BUILTIN_HIERARCHIES, &[]).unwrap();
        assert!(matches!(s[..], [Source::Builtin("lying", _)]));
        let e = sources(&names(&["lyin"]), BUILTIN_HIERARCHIES, &[]).unwrap_err();
        let msg = e.to_string();
        assert!(msg.starts_with("lyin: "), "{msg}");
        assert!(msg.contains("sitting, lying"), "{msg}");
    }

    #[test]
    fn a_folder_gives_its_toml_files_in_name_order() {
        let dir = tempfile::tempdir().unwrap();
        for (n, t) in BUILTIN_HIERARCHIES {
            std::fs::write(dir.path().join(format!("{n}.toml")), t).unwrap();
        }
        std::fs::write(dir.path().join("notes.txt"), "x").unwrap();
        let d = dir.path().display().to_string();
        let s = sources(&[d], BUILTIN_HIERARCHIES, &[]).unwrap();
        assert_eq!(
            s,
            vec![
                Source::File(dir.path().join("lying.toml")),
                Source::File(dir.path().join("sitting.toml")),
            ]
        );
    }

    #[test]
    fn the_set_is_every_body_at_every_height_with_every_hierarchy() {
        let agents = sources(&names(&["human", "child"]), BUILTIN_AGENTS, &[]).unwrap();
        let hs = sources(&[], BUILTIN_HIERARCHIES, &["sitting", "lying"]).unwrap();
        let set = load_set(&agents, &hs, &[1.2, 1.75]).unwrap();
        assert_eq!(set.len(), 8);
        assert_eq!(set[0].agent.name, "human");
        assert_eq!(set[0].agent.height, 1.2);
        assert_eq!(set[1].hierarchy.name, "lying");
        assert_eq!(set[2].agent.height, 1.75);
        assert_eq!(set[4].agent.name, "child");
        let ids = ids(&set);
        assert_eq!(ids[0], "sitting");
        assert!(ids.contains(&"lying".to_string()));
    }
}
