// Mesh-shader version of the rectangle raster in features.wgsl: one mesh workgroup per
// rectangle emits its four corners and two triangles; the fragment stage is the same.
enable wgpu_mesh_shader;

#import meshlight::math::saturate

struct Rect {
    // Pixel edges x0, y0, x1, y1.
    edges: vec4<u32>,
    // x: high word of the key (depth), y: low word (rectangle id).
    key: vec4<u32>,
}

struct MeshParams {
    // Target size in pixels.
    width: u32,
    height: u32,
    _pad: vec2<u32>,
}

@group(0) @binding(0) var<storage, read> rects: array<Rect>;
@group(0) @binding(1) var<storage, read_write> vis: array<atomic<u64>>;
@group(0) @binding(2) var<uniform> mesh_params: MeshParams;

struct VertexOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) @interpolate(flat) key: vec2<u32>,
}

struct PrimitiveOut {
    @builtin(triangle_indices) indices: vec3<u32>,
}

struct MeshOut {
    @builtin(vertices) vertices: array<VertexOut, 4>,
    @builtin(primitives) primitives: array<PrimitiveOut, 2>,
    @builtin(vertex_count) vertex_count: u32,
    @builtin(primitive_count) primitive_count: u32,
}

var<workgroup> mesh_out: MeshOut;

fn clip(x: u32, y: u32) -> vec4<f32> {
    let size = vec2<f32>(f32(mesh_params.width), f32(mesh_params.height));
    let ndc = vec2<f32>(f32(x), f32(min(y, mesh_params.height))) / size;
    return vec4<f32>(saturate(ndc.x) * 2.0 - 1.0, 1.0 - ndc.y * 2.0, 0.5, 1.0);
}

fn emit_rect(lane: u32, index: u32) {
    let r = rects[index];
    let x = select(r.edges.x, r.edges.z, lane == 1u || lane == 2u);
    let y = select(r.edges.y, r.edges.w, lane >= 2u);
    mesh_out.vertices[lane] = VertexOut(clip(x, y), r.key.xy);
    if lane == 0u {
        mesh_out.vertex_count = 4u;
        mesh_out.primitive_count = 2u;
        mesh_out.primitives[0].indices = vec3<u32>(0u, 1u, 2u);
        mesh_out.primitives[1].indices = vec3<u32>(0u, 2u, 3u);
    }
}

// Without a task stage: one mesh workgroup per rectangle, straight from the draw.
@mesh(mesh_out)
@workgroup_size(4)
fn rect_ms(@builtin(local_invocation_index) lane: u32, @builtin(workgroup_id) wg: vec3<u32>) {
    emit_rect(lane, wg.x);
}

struct TaskPayload {
    // Rectangles the task launched mesh workgroups for.
    count: u32,
}

var<task_payload> payload: TaskPayload;

// With a task stage: one task workgroup launches a mesh workgroup per rectangle.
@task
@payload(payload)
@workgroup_size(1)
fn rect_ts() -> @builtin(mesh_task_size) vec3<u32> {
    payload.count = arrayLength(&rects);
    return vec3<u32>(payload.count, 1u, 1u);
}

@mesh(mesh_out)
@payload(payload)
@workgroup_size(4)
fn rect_ms_task(@builtin(local_invocation_index) lane: u32, @builtin(workgroup_id) wg: vec3<u32>) {
    if wg.x < payload.count {
        emit_rect(lane, wg.x);
    }
}

@fragment
fn rect_fs(in: VertexOut) -> @location(0) vec4<f32> {
    let x = u32(in.pos.x);
    let y = u32(in.pos.y);
    atomicMax(&vis[y * mesh_params.width + x], (u64(in.key.x) << 32u) | u64(in.key.y));
    return vec4<f32>(1.0);
}
