// Calls the main functions of every shared module that needs no extra capability, and
// writes their results to a buffer so nothing is pruned.

#import meshlight::math
#import meshlight::view::{View, sphere_in_frustum, project_error_to_pixels, world_to_screen, position_from_depth, view_z_from_depth, pixel_to_uv}
#import meshlight::octahedral::{pack_octahedral_normal, unpack_octahedral_normal}
#import meshlight::meshlet::{Meshlet, Cluster, meshlet_position_location, meshlet_read_position_axis, meshlet_dequantize_position, meshlet_index_location, meshlet_local_index, meshlet_in_lod_cut}
#import meshlight::instance::{Instance, instance_transform_point, instance_transform_normal, instance_transform_sphere, instance_max_scale}
#import meshlight::visbuffer::{visbuffer_pack, visbuffer_depth, visbuffer_cluster, visbuffer_triangle, visbuffer_nearer, visbuffer_is_empty}
#import meshlight::light::{ClusterableObject, ClusterGrid, cluster_aabb, cluster_index, cluster_of_pixel, clusterable_intersects_cluster, z_slice_of_depth}

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> meshlets: array<Meshlet>;
@group(0) @binding(2) var<storage, read> clusters: array<Cluster>;
@group(0) @binding(3) var<storage, read> instances: array<Instance>;
@group(0) @binding(4) var<storage, read> words: array<u32>;
@group(0) @binding(5) var<uniform> grid: ClusterGrid;
@group(0) @binding(6) var<storage, read> objects: array<ClusterableObject>;
@group(0) @binding(7) var<storage, read_write> out: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let cluster = clusters[id.x];
    let meshlet = meshlets[cluster.meshlet];
    let instance = instances[cluster.instance];

    var delta = vec3(0u);
    for (var axis = 0u; axis < 3u; axis += 1u) {
        let at = meshlet_position_location(meshlet, id.y, axis);
        delta[axis] = meshlet_read_position_axis(meshlet, axis, vec2(words[at.x], words[at.x + 1u]), at.y);
    }
    let local = meshlet_dequantize_position(meshlet, delta, instance.position_grid);
    let world = instance_transform_point(instance, local);
    let corner = meshlet_index_location(meshlet, id.z, 1u);
    let index = meshlet_local_index(words[corner.x], corner.y);

    let normal = unpack_octahedral_normal(pack_octahedral_normal(
        instance_transform_normal(instance, math::safe_normalize(world, vec3(0.0, 0.0, 1.0)))));
    let sphere = instance_transform_sphere(instance, meshlet.bounding_sphere);
    let visible = sphere_in_frustum(view, sphere.xyz, sphere.w)
        && meshlet_in_lod_cut(view, instance.world_from_local, instance_max_scale(instance), meshlet, 1.0);
    let screen = world_to_screen(view, world);
    let vis = visbuffer_pack(screen.z, id.x, index);
    let other = visbuffer_pack(0.5, 3u, 2u);

    let c = cluster_of_pixel(grid, screen.xy, view_z_from_depth(view, screen.z));
    let hit = clusterable_intersects_cluster(view, objects[id.y], cluster_aabb(view, grid, c));
    let back = position_from_depth(view, pixel_to_uv(view, screen.xy), screen.z);

    out[id.x] = vec4(
        normal + back,
        f32(visible) + visbuffer_depth(vis) + f32(visbuffer_cluster(vis) + visbuffer_triangle(vis))
            + f32(visbuffer_nearer(vis, other)) + f32(visbuffer_is_empty(vis))
            + f32(cluster_index(grid, c)) + f32(hit) + f32(z_slice_of_depth(grid, screen.z))
            + project_error_to_pixels(view, sphere.xyz, sphere.w, meshlet.lod_error)
            + math::saturate(math::PI) + f32(math::div_ceil(id.x, 64u)),
    );
}
