// Calls the main functions of every shared module that needs no extra capability, and
// writes their results to a buffer so nothing is pruned.

#import meshlight::math
#import meshlight::dispatch::{fold_dispatch, linear_workgroup}
#import meshlight::view::{View, sphere_in_frustum, project_error_to_pixels, world_to_screen, position_from_depth, view_z_from_depth, pixel_to_uv}
#import meshlight::octahedral::{pack_octahedral_normal, unpack_octahedral_normal}
#import meshlight::meshlet::{Meshlet, MeshletGroup, Mesh, Cluster, meshlet_vertex_field, meshlet_position, meshlet_normal, meshlet_uv, meshlet_uv_word, meshlet_uv_location, meshlet_triangle_location, meshlet_triangle, meshlet_bounds, meshlet_level, lod_cut}
#import meshlight::instance_table::{instance_at, instance_total}
#import meshlight::scene_buffers::{meshes, meshlets, meshlet_groups, payload, materials}
#import meshlight::instance::{Instance, Material, instance_transform_point, instance_transform_normal, instance_transform_sphere, instance_max_scale}
#import meshlight::visbuffer::{visbuffer_pack, visbuffer_depth, visbuffer_cluster, visbuffer_triangle, visbuffer_nearer, visbuffer_is_empty}
#import meshlight::light::{ClusterableObject, ClusterGrid, cluster_index, cluster_of_pixel, z_slice_of_depth}
#import meshlight::froxel::{view_object, froxel_aabb, froxel_rect, rect_is_empty, object_touches_froxel}

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(2) var<storage, read> clusters: array<Cluster>;
@group(0) @binding(5) var<uniform> grid: ClusterGrid;
@group(0) @binding(6) var<storage, read> objects: array<ClusterableObject>;
@group(0) @binding(7) var<storage, read_write> out: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let cluster = clusters[id.x];
    let meshlet = meshlets[cluster.meshlet];
    let instance = instance_at(cluster.instance);

    let mesh = meshes[instance.mesh];
    var offset = vec3(0u);
    for (var axis = 0u; axis < 3u; axis += 1u) {
        let at = meshlet_vertex_field(meshlet, id.y, axis);
        offset[axis] = math::read_bits(vec2(payload[at.x], payload[at.x + 1u]), at.y, at.z);
    }
    let local = meshlet_position(meshlet, mesh.position_grid, offset);
    let nx = meshlet_vertex_field(meshlet, id.y, 3u);
    let ny = meshlet_vertex_field(meshlet, id.y, 4u);
    let mesh_normal = meshlet_normal(meshlet, vec2(
        math::read_bits(vec2(payload[nx.x], payload[nx.x + 1u]), nx.y, nx.z),
        math::read_bits(vec2(payload[ny.x], payload[ny.x + 1u]), ny.y, ny.z)));
    let block = meshlet_uv_word(meshlet);
    let uv_at = meshlet_uv_location(meshlet, id.y);
    let uv = meshlet_uv(meshlet, mesh.uv_grid, vec2(payload[block], payload[block + 1u]), vec2(payload[uv_at.x], payload[uv_at.x + 1u]), uv_at.y);
    let world = instance_transform_point(instance, local);
    let at = meshlet_triangle_location(meshlet, id.z);
    let index = meshlet_triangle(meshlet, id.z, vec2(payload[at.x], payload[at.x + 1u]), at.y).y;
    let group = meshlet_groups[meshlet.source_group];

    let normal = unpack_octahedral_normal(pack_octahedral_normal(
        instance_transform_normal(instance, math::safe_normalize(world, vec3(0.0, 0.0, 1.0)))));
    let sphere = instance_transform_sphere(instance, meshlet_bounds(meshlet));
    let visible = sphere_in_frustum(view, sphere.xyz, sphere.w)
        && lod_cut(view, instance.world_from_local, instance_max_scale(instance), group.lod_sphere, group.error, group.lod_sphere, group.error, 1.0);
    let screen = world_to_screen(view, world);
    let vis = visbuffer_pack(screen.z, id.x, index);
    let other = visbuffer_pack(0.5, 3u, 2u);

    let c = cluster_of_pixel(grid, screen.xy, view_z_from_depth(view, screen.z));
    let o = view_object(view, objects[id.y]);
    let hit = object_touches_froxel(o, froxel_aabb(view, grid, c)) && !rect_is_empty(froxel_rect(view, grid, o, c.z));
    let back = position_from_depth(view, pixel_to_uv(view, screen.xy), screen.z);

    out[id.x] = vec4(
        normal + back + mesh_normal + materials[instance.material].base_color.xyz + vec3(uv, f32(meshlet_level(meshlet))),
        f32(visible) + visbuffer_depth(vis) + f32(visbuffer_cluster(vis) + visbuffer_triangle(vis))
            + f32(visbuffer_nearer(vis, other)) + f32(visbuffer_is_empty(vis))
            + f32(cluster_index(grid, c)) + f32(hit) + f32(z_slice_of_depth(grid, screen.z))
            + project_error_to_pixels(view, sphere.xyz, sphere.w, group.error)
            + math::saturate(math::PI) + f32(math::div_ceil(id.x, 64u)) + f32(instance_total()) + f32(linear_workgroup(fold_dispatch(id.x, 7u), 3u)),
    );
}
