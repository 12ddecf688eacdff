//! One validated configuration of a run: which models (bodies at heights, hierarchies),
//! the scene-level numbers and how inputs are read. `detect`, `inspect` and `eval` build
//! it from the same flags in one place (`crate::cli`), the way ripgrep's `hiargs` does;
//! the library takes its parts. Every range is checked by the functions here, which the
//! command line's parsers and the model loaders share, so a value the parser accepts is
//! one the loader accepts.

use std::ops::RangeInclusive;

use afford::detect::{DetectConfig, DEFAULT_VOXEL};
use afford::input::InputOptions;
use afford::model::agent::check_height;
use afford::model::check_range;
use afford::model::set::ModelChoice;

/// Voxel edges a scene may have, metres: finer than 2 mm only records sensor noise (and
/// the grids of a room outgrow memory); coarser than 10 cm is wider than a limb, so the
/// body passes through thin parts.
pub const VOXEL_RANGE: RangeInclusive<f64> = 0.002..=0.1;

/// Checks a voxel edge (metres) against [`VOXEL_RANGE`].
pub fn check_voxel(voxel: f64) -> Result<f64, String> {
    check_range(voxel, &VOXEL_RANGE, "voxel size")
}

/// A value of the configuration outside its range.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum SettingsError {
    /// A body height outside [`afford::model::agent::HEIGHT_RANGE`].
    #[error("--height: {0}")]
    Height(String),
    /// A voxel edge outside [`VOXEL_RANGE`].
    #[error("--voxel: {0}")]
    Voxel(String),
}

/// Everything `detect`, `inspect` and `eval` share, validated.
#[derive(Debug, Clone, Default)]
pub struct Settings {
    /// Bodies and hierarchies.
    pub models: ModelChoice,
    /// Scene-level numbers, voxel-relative ones derived from the voxel.
    pub detect: DetectConfig,
    /// How inputs are read and brought into the world frame.
    pub input: InputOptions,
}

impl Settings {
    /// Checks the heights and the voxel edge (metres; `None` for the default) and derives
    /// the scene-level numbers from the voxel ([`DetectConfig::for_voxel`]).
    pub fn new(
        models: ModelChoice,
        voxel: Option<f64>,
        input: InputOptions,
    ) -> Result<Settings, SettingsError> {
        for &h in &models.heights {
            check_height(h).map_err(SettingsError::Height)?;
        }
        let voxel = check_voxel(voxel.unwrap_or(DEFAULT_VOXEL)).map_err(SettingsError::Voxel)?;
        Ok(Settings {
            models,
            detect: DetectConfig::for_voxel(voxel),
            input,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use afford::model::agent::HEIGHT_RANGE;

    #[test]
    fn the_parser_range_is_the_loader_range() {
        // Both ends are accepted by the check and by the loader; just outside is refused by both.
        for h in [*HEIGHT_RANGE.start(), *HEIGHT_RANGE.end()] {
            let s = Settings::new(
                ModelChoice {
                    heights: vec![h],
                    ..Default::default()
                },
                None,
                Default::default(),
            )
            .unwrap();
            assert_eq!(s.models.load().unwrap()[0].agent.height, h);
        }
        for h in [0.29, 3.01, f64::NAN] {
            let choice = ModelChoice {
                heights: vec![h],
                ..Default::default()
            };
            let e = Settings::new(choice.clone(), None, Default::default()).unwrap_err();
            assert_eq!(
                e.to_string(),
                format!("--height: body height {h} m is outside 0.3-3.0 m")
            );
            assert!(choice.load().is_err());
        }
    }

    #[test]
    fn voxel_relative_numbers_follow_the_voxel() {
        let d = Settings::default().detect;
        assert_eq!(d.scene.voxel_size, DEFAULT_VOXEL);
        assert_eq!(d.contact.resolution, 0.005);
        assert_eq!(d.segment.grow_distance, 0.03);
        let s = Settings::new(ModelChoice::default(), Some(0.05), Default::default()).unwrap();
        assert_eq!(s.detect.scene.voxel_size, 0.05);
        assert!((s.detect.contact.resolution - 0.0125).abs() < 1e-12);
        assert!((s.detect.segment.grow_distance - 0.075).abs() < 1e-12);
        // The numbers that are not voxel-relative stay.
        assert_eq!(s.detect.segment.floor_height, d.segment.floor_height);
        let e = Settings::new(ModelChoice::default(), Some(0.2), Default::default()).unwrap_err();
        assert_eq!(
            e.to_string(),
            "--voxel: voxel size 0.2 m is outside 0.002-0.1 m"
        );
    }
}
