#![no_main]
//! Agent and affordance-hierarchy TOML parsers on arbitrary text.

use std::path::Path;
use std::sync::OnceLock;

use afford::model::agent::Agent;
use afford::model::hierarchy::Hierarchy;
use libfuzzer_sys::fuzz_target;

fn builtin() -> &'static Agent {
    static AGENT: OnceLock<Agent> = OnceLock::new();
    AGENT.get_or_init(|| {
        Agent::from_toml(afford::model::set::BUILTIN_AGENT, Path::new("human.toml"), 1.75)
            .expect("builtin agent")
    })
}

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let _ = Agent::from_toml(text, Path::new("f.toml"), 1.75);
    let _ = Hierarchy::from_toml(text, Path::new("f.toml"), builtin());
});
