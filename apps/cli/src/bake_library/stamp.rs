//! The stamp beside each output of a directory bake (`crate.mlasset.key`): what the
//! asset was baked from, so that a later run can skip it.
//!
//! The key is the scene crate's cache key ([`cache::key`]: an XXH3 hash of the file's
//! bytes, the build options, the asset format and the builder's revision) of the mesh
//! file and, for glTF, of each buffer file it names: a `.gltf` whose `.bin` changed is
//! baked again although its own bytes did not change. The checksum is the asset's own,
//! so a damaged or replaced output is baked again whatever its stamp says.

use super::AssetStats;
use meshlight::scene::cache::{self, Source};
use meshlight::scene::input::{MAX_INPUT_BYTES, read_file};
use meshlight::scene::load::referenced_path;
use meshlight::scene::{BuildOptions, MeshletAsset, SceneError};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Appended to the output's name.
pub const STAMP_SUFFIX: &str = ".key";
/// First line of a stamp, so that a stray file of the same name is not taken for one.
const STAMP_HEADER: &str = "meshlight bake stamp 2";

pub fn stamp_of(output: &Path) -> PathBuf {
    let mut name = output.as_os_str().to_owned();
    name.push(STAMP_SUFFIX);
    PathBuf::from(name)
}

/// The key of `input` baked with `options`: its cache key, then those of the buffer
/// files a glTF names, joined with `+`.
pub fn input_key(input: &Path, options: &BuildOptions) -> Result<String, SceneError> {
    let key = |path: &Path| cache::key(&Source::File(path.to_path_buf()), options);
    let mut text = format!("{:016x}", key(input)?);
    for buffer in external_buffers(input) {
        // One the loader cannot read either refuses the bake with its own message.
        if let Ok(k) = key(&buffer) {
            let _ = write!(text, "+{k:016x}");
        }
    }
    Ok(text)
}

/// The checksum in an asset's header.
pub fn checksum(asset: &MeshletAsset) -> u64 {
    let c = asset.header().checksum;
    u64::from(c[0]) | (u64::from(c[1]) << 32)
}

pub fn stamp_text(key: &str, asset: &MeshletAsset, fallback_groups: Option<u32>) -> String {
    let mut s = format!(
        "{STAMP_HEADER}\nkey {key}\nchecksum {:016x}\n",
        checksum(asset)
    );
    if let Some(n) = fallback_groups {
        let _ = writeln!(s, "fallback_groups {n}");
    }
    s
}

/// The output's numbers if its stamp holds `key` and the asset loads (validated) with
/// the stamped checksum; `None` means bake it.
pub fn up_to_date(output: &Path, key: &str) -> Option<AssetStats> {
    let text = std::fs::read_to_string(stamp_of(output)).ok()?;
    let mut lines = text.lines();
    if lines.next()? != STAMP_HEADER {
        return None;
    }
    let fields: BTreeMap<&str, &str> = lines.filter_map(|l| l.split_once(' ')).collect();
    if *fields.get("key")? != key {
        return None;
    }
    let asset = MeshletAsset::load(output).ok()?;
    if u64::from_str_radix(fields.get("checksum")?, 16).ok()? != checksum(&asset) {
        return None;
    }
    Some(AssetStats {
        fallback_groups: fields.get("fallback_groups").and_then(|n| n.parse().ok()),
        ..super::stats_of(&asset)
    })
}

/// The buffer files a `.gltf` or `.glb` names by relative URI, in its order: those the
/// loader reads beside the model, found by the loader's own containment rule
/// ([`referenced_path`]: no scheme, no absolute path, nothing leaving the model's folder,
/// links included), so a stamp never opens what the loader would refuse. `data:` URIs are
/// in the file's own bytes.
fn external_buffers(input: &Path) -> Vec<PathBuf> {
    let is = |ext: &str| {
        input
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case(ext))
    };
    if !(is("gltf") || is("glb")) {
        return Vec::new();
    }
    let Some(json) = read_file(input, MAX_INPUT_BYTES)
        .ok()
        .and_then(|b| gltf_json(&b))
    else {
        return Vec::new();
    };
    json.get("buffers")
        .and_then(|b| b.as_array())
        .into_iter()
        .flatten()
        .filter_map(|b| b.get("uri")?.as_str())
        .filter(|uri| !uri.starts_with("data:"))
        .filter_map(|uri| referenced_path(input, uri).ok())
        .collect()
}

/// The JSON of a `.gltf`, or of a `.glb`'s first chunk.
fn gltf_json(bytes: &[u8]) -> Option<serde_json::Value> {
    let json = if bytes.starts_with(b"glTF") {
        let word = |at: usize| {
            let b = bytes.get(at..at + 4)?;
            Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
        };
        let (length, kind) = (word(12)?, bytes.get(16..20)?);
        if kind != b"JSON" {
            return None;
        }
        bytes.get(20..20usize.checked_add(length)?)?
    } else {
        bytes
    };
    serde_json::from_slice(json).ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bake_library::scratch::scratch;

    /// A buffer reached through a link that leads out of the model's folder is not
    /// followed: the loader refuses it, so the stamp never opens it.
    #[cfg(unix)]
    #[test]
    fn a_buffer_linked_outside_the_models_folder_is_not_opened() {
        let dir = scratch("stamp-link");
        let model = dir.join("model");
        std::fs::create_dir_all(&model).unwrap();
        std::fs::write(dir.join("outside.bin"), [0u8; 4]).unwrap();
        std::os::unix::fs::symlink(dir.join("outside.bin"), model.join("link.bin")).unwrap();
        std::fs::write(model.join("inside.bin"), [0u8; 4]).unwrap();
        let gltf = model.join("m.gltf");
        std::fs::write(
            &gltf,
            r#"{"asset":{"version":"2.0"},"buffers":[{"uri":"link.bin","byteLength":4},{"uri":"inside.bin","byteLength":4}]}"#,
        )
        .unwrap();
        assert_eq!(external_buffers(&gltf), [model.join("inside.bin")]);
    }

    #[test]
    fn the_buffers_a_gltf_names_beside_it_are_found_and_no_others() {
        let dir = scratch("stamp");
        let json = r#"{"asset":{"version":"2.0"},"buffers":[
            {"uri":"data:application/octet-stream;base64,AAAA","byteLength":3},
            {"uri":"my%20mesh.bin","byteLength":4},
            {"uri":"sub/./b.bin","byteLength":4},
            {"uri":"../escape.bin","byteLength":4},
            {"uri":"/etc/hostname","byteLength":4},
            {"uri":"file:///etc/hostname","byteLength":4},
            {"byteLength":4}]}"#;
        let gltf = dir.join("m.gltf");
        std::fs::write(&gltf, json).unwrap();
        let expected = [dir.join("my mesh.bin"), dir.join("sub/./b.bin")];
        assert_eq!(external_buffers(&gltf), expected);
        // The same JSON as a .glb's first chunk.
        let mut glb = b"glTF".to_vec();
        glb.extend(2u32.to_le_bytes());
        glb.extend(0u32.to_le_bytes());
        glb.extend((json.len() as u32).to_le_bytes());
        glb.extend(b"JSON");
        glb.extend(json.as_bytes());
        let glb_path = dir.join("m.glb");
        std::fs::write(&glb_path, glb).unwrap();
        assert_eq!(external_buffers(&glb_path), expected);
        // Other formats name no buffers, even with glTF bytes.
        let obj = dir.join("m.obj");
        std::fs::write(&obj, json).unwrap();
        assert!(external_buffers(&obj).is_empty());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
