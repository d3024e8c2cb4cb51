#define_import_path meshlight::cluster_triangle

// Triangle `t` of a listed cluster, found through the scene's buffers: the instance that
// places it, its meshlet and mesh, and its corners' vertex indices in the meshlet. The
// software rasteriser starts every triangle it covers here, and the shading resolve
// every triangle a pixel shows, so both decode the same corners.

#import meshlight::meshlet::{Meshlet, Mesh, Cluster, meshlet_triangle_location, meshlet_triangle}
#import meshlight::instance::Instance
#import meshlight::instance_table::instance_at
#import meshlight::scene_buffers::{meshes, meshlets, payload}

struct ClusterTriangle {
    instance: Instance,
    m: Meshlet,
    mesh: Mesh,
    // Its corners' vertex indices in the meshlet.
    corners: vec3<u32>,
}

fn cluster_triangle(cluster: Cluster, t: u32) -> ClusterTriangle {
    let instance = instance_at(cluster.instance);
    let m = meshlets[cluster.meshlet];
    let mesh = meshes[instance.mesh];
    let at = meshlet_triangle_location(m, t);
    let corners = meshlet_triangle(m, t, vec2(payload[at.x], payload[at.x + 1u]), at.y);
    return ClusterTriangle(instance, m, mesh, corners);
}
