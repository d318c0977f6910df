//! Generated dwellings where a scene file is asked for: `dwelling:SEED` (generated into the
//! cache on first use), and which seeds are held out for measuring policies.

use std::path::{Path, PathBuf};

use super::{generate, shipped_catalogue_dir, Catalogue, DwellingSettings, DWELLING_VERSION};

/// The scene-source prefix that names a generated dwelling where a scene file is asked for:
/// `dwelling:SEED`.
pub(crate) const DWELLING_SOURCE: &str = "dwelling:";

/// Dwelling seeds from this one up are held out: a policy is measured on them and never
/// trained on them (training refuses them), and the generator was not developed on them.
pub(crate) const HELD_OUT_SEEDS_FROM: u64 = 1_000_000;

/// The seed of the generated dwelling a scene is, if it is one: `dwelling:SEED` as written, or
/// a scene file whose sidecar (`<stem>.json` beside it) records the generator's seed.
pub(crate) fn dwelling_seed(source: &str, path: &Path) -> Option<u64> {
    if let Some(seed) = source.strip_prefix(DWELLING_SOURCE) {
        return seed.trim().parse().ok();
    }
    generated_sidecar(path)?
        .1
        .get("generator")?
        .get("seed")?
        .as_u64()
}

/// The sidecar of a scene file (`<stem>.json` beside it), its bytes and its JSON, where egogen
/// generated the scene (`generator.tool` is `egogen scene generate`); none otherwise.
pub(crate) fn generated_sidecar(scene: &Path) -> Option<(Vec<u8>, serde_json::Value)> {
    let bytes = std::fs::read(scene.with_extension("json")).ok()?;
    let json: serde_json::Value = serde_json::from_slice(&bytes).ok()?;
    (json.get("generator")?.get("tool")?.as_str()? == "egogen scene generate")
        .then_some((bytes, json))
}

/// The file a scene source names: a path as it is (joined to `base`), or for `dwelling:SEED`
/// the dwelling of that seed (default settings, the shipped catalogue), generated into the
/// cache on first use (`<cache>/dwellings/v<version>-<catalogue sha256, 12 hex>/dwelling_<seed>.glb`,
/// its sidecar beside it) and the same file after.
pub(crate) fn scene_source(source: &str, base: &Path) -> Result<PathBuf, String> {
    let Some(seed) = source.strip_prefix(DWELLING_SOURCE) else {
        return Ok(base.join(source));
    };
    let seed: u64 = seed.trim().parse().map_err(|_| {
        format!("`{source}`: expected dwelling:SEED with SEED a whole number from 0 to 2^64 − 1")
    })?;
    let catalogue = Catalogue::load(&shipped_catalogue_dir()).map_err(|e| e.to_string())?;
    let dir = crate::paths::cache_dir().join("dwellings").join(format!(
        "v{DWELLING_VERSION}-{}",
        catalogue.own().source_sha256.get(..12).unwrap_or("unknown")
    ));
    let glb = dir.join(format!("dwelling_{seed}.glb"));
    if !glb.is_file() {
        // Written under a name of this process's own and renamed into place (the sidecar
        // first): takes resolving the same dwelling at once each write whole files, the same
        // bytes, and the last rename wins.
        let own = dir.join(format!(".dwelling_{seed}.{}.glb", std::process::id()));
        generate(&DwellingSettings::default(), &catalogue, seed)
            .and_then(|d| d.write_glb(&catalogue, &own))
            .map_err(|e| format!("`{source}`: {e}"))?;
        std::fs::rename(own.with_extension("json"), glb.with_extension("json"))
            .and_then(|()| std::fs::rename(&own, &glb))
            .map_err(|e| format!("`{source}`: moving it into {}: {e}", dir.display()))?;
    }
    Ok(glb)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_dwellings_seed_is_read_from_its_source_or_its_sidecar() {
        let dir = tempfile::tempdir().unwrap();
        let glb = dir.path().join("home.glb");
        assert_eq!(dwelling_seed("dwelling:1000000", &glb), Some(1_000_000));
        assert_eq!(dwelling_seed("dwelling: 7", &glb), Some(7));
        // No sidecar, or one another tool wrote: not a generated dwelling.
        assert_eq!(dwelling_seed("home.glb", &glb), None);
        let sidecar = dir.path().join("home.json");
        std::fs::write(&sidecar, r#"{"generator": {"tool": "blender", "seed": 3}}"#).unwrap();
        assert_eq!(dwelling_seed("home.glb", &glb), None);
        std::fs::write(
            &sidecar,
            r#"{"generator": {"tool": "egogen scene generate", "version": 1, "seed": 1000001}}"#,
        )
        .unwrap();
        assert_eq!(dwelling_seed("home.glb", &glb), Some(1_000_001));
        assert!(dwelling_seed("home.glb", &glb).unwrap() >= HELD_OUT_SEEDS_FROM);
    }
}
