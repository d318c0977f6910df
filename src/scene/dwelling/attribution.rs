//! The attribution a dwelling, a take or a campaign carries when it places models of an opt-in
//! (CC-BY) furniture library: a Markdown file naming each such model, its creator, its library's
//! copyright and licence, and what was changed. Made from dwelling sidecars alone (each object's
//! model, name, creator and library; each added library's licence, deed and copyright), so that
//! whatever holds a sidecar can write it; nothing is written where every model is CC0.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::catalogue::Library;

/// The file a take or a campaign folder carries its attribution in.
pub(crate) const ATTRIBUTION_FILE: &str = "ATTRIBUTION.md";

/// The attribution beside a dwelling's GLB: `<stem>.attribution.md`.
pub(crate) fn file_beside(glb: &Path) -> PathBuf {
    glb.with_extension("attribution.md")
}

#[derive(Deserialize)]
struct SidecarView {
    #[serde(default)]
    catalogue: CatalogueView,
    #[serde(default)]
    objects: Vec<ObjectView>,
}

#[derive(Default, Deserialize)]
struct CatalogueView {
    #[serde(default)]
    added: Vec<Library>,
}

#[derive(Deserialize)]
struct ObjectView {
    model: Option<String>,
    model_name: Option<String>,
    creator: Option<String>,
    library: Option<String>,
}

/// The attribution for the dwellings of these sidecars (`dwelling.json` bytes), or none where
/// none places a model of an added library. An object naming a library its sidecar does not
/// list is an error.
pub(crate) fn of_sidecars(sidecars: &[&[u8]]) -> Result<Option<String>, String> {
    // library name → (the library, model id → (title, creator))
    let mut used: BTreeMap<String, (Library, BTreeMap<String, (String, String)>)> = BTreeMap::new();
    for bytes in sidecars {
        let sidecar: SidecarView =
            serde_json::from_slice(bytes).map_err(|e| format!("not a dwelling sidecar: {e}"))?;
        for o in &sidecar.objects {
            let (Some(name), Some(model)) = (&o.library, &o.model) else {
                continue;
            };
            let library = sidecar
                .catalogue
                .added
                .iter()
                .find(|l| &l.name == name)
                .ok_or_else(|| {
                    format!("object of model `{model}` names the library `{name}`, which `catalogue.added` does not list")
                })?;
            used.entry(name.clone())
                .or_insert_with(|| (library.clone(), BTreeMap::new()))
                .1
                .insert(
                    model.clone(),
                    (
                        o.model_name.clone().unwrap_or_default(),
                        o.creator.clone().unwrap_or_default(),
                    ),
                );
        }
    }
    if used.is_empty() {
        return Ok(None);
    }
    let mut text = String::from(
        "# Attribution\n\n\
         The generated dwellings here place furniture models under Creative Commons Attribution \
         licences, listed below with their creators. They are models of Sweet Home 3D's furniture \
         libraries (Debian package `sweethome3d-furniture` 1.8-1), changed by egogen: converted to \
         glTF by `tools/furniture_catalogue.py` (scaled to the library's stated size, meshes \
         decimated, textures resized to at most 512 px), placed in dwellings egogen generated, and \
         rendered in the images. The licence does not endorse this use.\n",
    );
    for (name, (library, models)) in &used {
        text.push_str(&format!(
            "\n## {name}: {} ({})\n\nCopyright {}. Source: {} (sha256 {}).\n\n| model | title | creator |\n| --- | --- | --- |\n",
            library.licence,
            library.licence_url.as_deref().unwrap_or("licence deed not given"),
            library.copyright.as_deref().unwrap_or("not given"),
            library.source,
            library.source_sha256,
        ));
        for (id, (title, creator)) in models {
            text.push_str(&format!("| `{id}` | {title} | {creator} |\n"));
        }
    }
    Ok(Some(text))
}

/// The attribution a take made in the scene file `scene` carries: that of its sidecar
/// (`<stem>.json` beside it) where it is a generated dwelling's, none otherwise.
pub(crate) fn of_scene(scene: &Path) -> Result<Option<String>, String> {
    let Some((bytes, _)) = super::source::generated_sidecar(scene) else {
        return Ok(None);
    };
    of_sidecars(&[&bytes]).map_err(|e| format!("{}: {e}", scene.with_extension("json").display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sidecar(objects: &str) -> String {
        format!(
            r#"{{"generator": {{"tool": "egogen scene generate"}},
                "catalogue": {{"library": "BlendSwap-CC-0", "licence": "CC0-1.0", "source": "s", "source_sha256": "0",
                  "added": [{{"library": "Scopia", "licence": "CC-BY-3.0",
                     "licence_url": "https://creativecommons.org/licenses/by/3.0/",
                     "copyright": "2010-2012, Scopia", "source": "Debian", "source_sha256": "ab"}}]}},
                "objects": [{objects}]}}"#
        )
    }

    #[test]
    fn only_models_of_added_libraries_are_attributed_once_each() {
        let cc0 = r#"{"model": "chair", "model_name": "Chair", "creator": "x", "library": null}"#;
        let by = r#"{"model": "scopia_table4", "model_name": "Table", "creator": "Scopia"}"#;
        let by_lib = by.replace('}', r#", "library": "Scopia"}"#);
        assert_eq!(of_sidecars(&[sidecar(cc0).as_bytes()]).unwrap(), None);
        assert_eq!(of_sidecars(&[sidecar(by).as_bytes()]).unwrap(), None);
        let two = sidecar(&format!("{cc0}, {by_lib}, {by_lib}"));
        let text = of_sidecars(&[two.as_bytes(), two.as_bytes()])
            .unwrap()
            .unwrap();
        assert_eq!(text.matches("scopia_table4").count(), 1, "{text}");
        assert!(
            text.contains("| `scopia_table4` | Table | Scopia |"),
            "{text}"
        );
        assert!(
            text.contains("## Scopia: CC-BY-3.0 (https://creativecommons.org/licenses/by/3.0/)")
        );
        assert!(text.contains("Copyright 2010-2012, Scopia."), "{text}");
        assert!(!text.contains("`chair`"), "{text}");
        let unknown = sidecar(&by.replace('}', r#", "library": "KatorLegaz"}"#));
        let err = of_sidecars(&[unknown.as_bytes()]).unwrap_err();
        assert!(
            err.contains("KatorLegaz") && err.contains("catalogue.added"),
            "{err}"
        );
    }
}
