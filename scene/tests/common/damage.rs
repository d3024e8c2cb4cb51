//! Damaging a baked asset the way a bit flip or a hostile writer would, while keeping its
//! size and checksum valid, so that only the structural checks can notice.

use meshlight_scene::asset::checksum::seal;
use meshlight_scene::asset::format::AssetHeader;
use meshlight_scene::{BuildOptions, MeshletAsset, SceneError, build_asset, procedural_mesh};
use std::path::Path;

/// A small procedural mesh baked with the default options, as words.
pub fn good_words() -> Vec<u32> {
    let built = build_asset(&procedural_mesh(12), &BuildOptions::default(), &mut |_| {}).unwrap();
    bytemuck::cast_slice(built.asset.bytes()).to_vec()
}

/// Record `i` of the section `section`, whose records are `T`s (meshlets, groups or
/// nodes), to damage in place.
pub fn record_mut<T: bytemuck::Pod>(words: &mut [u32], section: usize, i: usize) -> &mut T {
    let h: &AssetHeader = bytemuck::from_bytes(bytemuck::cast_slice(&words[..AssetHeader::WORDS]));
    let first = h.sections[section].offset as usize;
    let n = size_of::<T>() / 4;
    bytemuck::from_bytes_mut(bytemuck::cast_slice_mut(
        &mut words[first + i * n..first + (i + 1) * n],
    ))
}

/// Rewrites the header's size and checksum to match the (damaged) words.
pub fn reseal(words: &mut [u32]) {
    let size = words.len() as u64 * 4;
    let h: &mut AssetHeader =
        bytemuck::from_bytes_mut(bytemuck::cast_slice_mut(&mut words[..AssetHeader::WORDS]));
    h.file_size = [size as u32, (size >> 32) as u32];
    seal(words);
}

/// Applies `edit` to [`good_words`], reseals and loads as `bad.mlasset`; expects an
/// `AssetField` error naming `field` whose message names the file and says to re-bake,
/// and returns that message.
pub fn refused(what: &str, field: &str, edit: impl FnOnce(&mut Vec<u32>)) -> String {
    let mut w = good_words();
    edit(&mut w);
    reseal(&mut w);
    let len = w.len() as u64 * 4;
    let err = MeshletAsset::from_words(w, len, Path::new("bad.mlasset")).unwrap_err();
    let msg = err.to_string();
    match &err {
        SceneError::AssetField { field: f, .. } => assert!(
            f.contains(field),
            "{what}: named {f:?}, expected {field:?}: {msg}"
        ),
        other => panic!("{what}: {other:?}"),
    }
    assert!(
        msg.contains("bad.mlasset") && msg.contains("re-bake"),
        "{what}: {msg}"
    );
    msg
}

/// Like [`refused`], and the message also says `needle`.
pub fn refused_saying(what: &str, field: &str, needle: &str, edit: impl FnOnce(&mut Vec<u32>)) {
    let msg = refused(what, field, edit);
    assert!(
        msg.contains(needle),
        "{what}: {needle:?} missing from: {msg}"
    );
}
