//! Opening an asset for streaming: only its resident part is read and checked, and each
//! page is checked when it is read, as strictly as a whole file's load checks it.

mod common;

use meshlight_scene::asset::format::SECTION_PAYLOAD;
use meshlight_scene::{BuildOptions, MeshletAsset, SceneError, build_asset, procedural_mesh};

fn built() -> MeshletAsset {
    build_asset(&procedural_mesh(16), &BuildOptions::default(), &mut |_| {})
        .unwrap()
        .asset
}

/// Page `group`'s words in a whole asset's payload.
fn page_words(asset: &MeshletAsset, group: usize) -> Vec<u32> {
    asset.payload()[asset.pages()[group].range()].to_vec()
}

#[test]
fn the_resident_part_is_all_that_is_read_and_every_page_checks_against_it() {
    let whole = built();
    let dir = common::scratch("open-resident");
    let path = dir.join("knot.mlasset");
    whole.save(&path).unwrap();
    let opened = MeshletAsset::open_resident(&path).unwrap();
    assert_eq!(opened.page_file(), Some(path.as_path()));
    assert_eq!(whole.page_file(), None);
    assert!(opened.is_verified());
    assert_eq!(opened.bytes().len() as u64, whole.resident_bytes());
    assert!(
        opened.bytes().len() < whole.bytes().len() / 4,
        "the roots are a small part"
    );
    assert_eq!(
        opened.payload().len(),
        whole.header().resident_words as usize
    );
    assert_eq!(opened.meshlets(), whole.meshlets());
    assert_eq!(opened.groups(), whole.groups());
    assert_eq!(opened.pages(), whole.pages());
    assert_eq!(opened.nodes(), whole.nodes());
    assert_eq!(opened.held_meshlets(), whole.header().root_count as usize);
    for g in 0..whole.pages().len() {
        opened
            .check_page(g, &page_words(&whole, g))
            .unwrap_or_else(|e| panic!("page {g}: {e:?}"));
    }
    // A page of the wrong length, or past the last, is refused.
    let mut short = page_words(&whole, 0);
    short.pop();
    let err = opened.check_page(0, &short).unwrap_err();
    assert!(
        err.problem.contains("words where its record says"),
        "{err:?}"
    );
    assert!(opened.check_page(whole.pages().len(), &short).is_err());
    // Its resident part is not a file to save.
    let err = opened.save(&dir.join("copy.mlasset")).unwrap_err();
    assert!(err.to_string().contains("opened for streaming"), "{err}");
}

#[test]
fn damage_in_a_page_waits_for_the_page_and_damage_in_the_resident_part_does_not() {
    let whole = built();
    let good = whole.bytes().to_vec();
    let dir = common::scratch("open-resident-damage");
    let payload = whole.header().sections[SECTION_PAYLOAD].offset as usize * 4;
    let last = whole.pages().len() - 1;
    // A flipped byte in the last page: a whole load refuses it, a streamed open does not
    // read it (the page's checksum refuses it when it is read).
    let mut bad = good.clone();
    bad[payload + whole.pages()[last].first_word as usize * 4 + 1] ^= 0x20;
    let path = dir.join("page.mlasset");
    std::fs::write(&path, &bad).unwrap();
    assert!(matches!(
        MeshletAsset::load(&path),
        Err(SceneError::AssetPageChecksum { .. })
    ));
    MeshletAsset::open_resident(&path).unwrap();
    // In the resident part: refused at open.
    let mut bad = good.clone();
    bad[whole.resident_bytes() as usize - 9] ^= 0x04;
    let path = dir.join("resident.mlasset");
    std::fs::write(&path, &bad).unwrap();
    let err = MeshletAsset::open_resident(&path).unwrap_err();
    assert!(matches!(err, SceneError::AssetChecksum { .. }), "{err:?}");
    // Truncated, or too short for a header: the file's size is checked without reading
    // the pages.
    for (name, len) in [("cut.mlasset", good.len() - 4), ("tiny.mlasset", 20)] {
        let path = dir.join(name);
        std::fs::write(&path, &good[..len]).unwrap();
        let err = MeshletAsset::open_resident(&path).unwrap_err();
        assert!(
            matches!(err, SceneError::AssetTruncated { .. }),
            "{name}: {err:?}"
        );
    }
    let err = MeshletAsset::open_resident(&dir.join("missing.mlasset")).unwrap_err();
    assert!(matches!(err, SceneError::Io { .. }), "{err:?}");
}

/// A page's check agrees with the whole file's: random bit flips in a page (the
/// checksums resealed, as a hostile writer would) are refused by `check_page` exactly
/// when loading the whole file refuses them or `inspect`'s per-meshlet checks report
/// them; never a panic.
#[test]
fn a_damaged_page_is_refused_exactly_when_the_whole_file_would_be() {
    let whole = built();
    let words: Vec<u32> = bytemuck::cast_slice(whole.bytes()).to_vec();
    let payload = whole.header().sections[SECTION_PAYLOAD].offset as usize;
    let dir = common::scratch("open-resident-flips");
    let path = dir.join("knot.mlasset");
    whole.save(&path).unwrap();
    let opened = MeshletAsset::open_resident(&path).unwrap();
    let mut state = 0x2545_f491u32;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 17;
        state ^= state << 5;
        state
    };
    let (mut refused, mut accepted) = (0, 0);
    for round in 0..400 {
        let group = next() as usize % whole.pages().len();
        let page = whole.pages()[group];
        let mut w = words.clone();
        for _ in 0..1 + round % 3 {
            let at = payload + page.first_word as usize + next() as usize % page.words as usize;
            w[at] ^= 1 << (next() % 32);
        }
        let damaged = w[payload + page.first_word as usize..][..page.words as usize].to_vec();
        let by_page = opened.check_page(group, &damaged);
        common::damage::reseal(&mut w);
        let len = w.len() as u64 * 4;
        let by_file = match MeshletAsset::from_words(w, len, &path) {
            Err(e) => Some(e.to_string()),
            Ok(asset) => meshlight_scene::verify::verify(&asset)
                .into_iter()
                .find(|p| p.contains("refers past its") || p.contains("culling sphere")),
        };
        assert_eq!(
            by_page.is_err(),
            by_file.is_some(),
            "round {round}, page {group}: page check {by_page:?}, whole file {by_file:?}"
        );
        match by_page {
            Ok(()) => accepted += 1,
            Err(_) => refused += 1,
        }
    }
    eprintln!("{refused} refused, {accepted} accepted");
    assert!(
        refused > 40 && accepted > 40,
        "{refused} refused, {accepted} accepted"
    );
}
