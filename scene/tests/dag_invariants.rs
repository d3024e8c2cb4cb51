mod common;

use meshlight_scene::{BuildOptions, build_asset, load::load_mesh, verify};

#[test]
fn probe_bunny() {
    let Some(dir) = common::shared_meshes() else { return };
    for name in common::SHARED_MESHES {
        let mesh = load_mesh(&dir.join(name)).unwrap();
        let built = build_asset(&mesh, &BuildOptions::default(), &mut |_| {}).unwrap();
        let h = built.asset.header();
        println!("{name}: tris {} dag {:?} total {:?} levels {} roots {} lod0 {} bytes/tri {:.2} stats {:?}",
            h.lod0_triangles, built.dag_time, built.total_time, h.level_count, h.root_count, h.lod0_meshlets,
            built.asset.bytes().len() as f64 / h.lod0_triangles as f64, verify::level_stats(&built.asset));
        println!("problems: {:?}", verify::verify(&built.asset).iter().take(5).collect::<Vec<_>>());
    }
}
