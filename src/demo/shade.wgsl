// Demo shading from the visibility buffer: the triangle's face normal, lit by one
// directional light and a sky/ground ambient, packed to RGBA8.

struct ShadeParams {
    // World-space direction towards the light.
    light_dir: vec4<f32>,
    // Width of the image in pixels.
    width: u32,
    // Height of the image in pixels.
    height: u32,
    // Threads per row of the 2-D dispatch.
    threads_per_row: u32,
    // Padding to 16 bytes.
    _pad: u32,
}

@group(0) @binding(0) var<storage, read> positions: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read> indices: array<u32>;
@group(0) @binding(2) var<storage, read> visbuffer: array<vec2<u32>>;
@group(0) @binding(3) var<storage, read_write> image: array<u32>;
@group(0) @binding(4) var<uniform> params: ShadeParams;

@compute @workgroup_size(64)
fn shade(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.y * params.threads_per_row + id.x;
    if i >= params.width * params.height {
        return;
    }
    // Little-endian: word 0 holds the low 32 bits (the triangle), word 1 the depth.
    let vis = visbuffer[i];
    var color: vec3<f32>;
    if vis.x == 0u {
        let v = f32(i / params.width) / f32(params.height);
        color = mix(vec3(0.20, 0.24, 0.30), vec3(0.05, 0.06, 0.08), v);
    } else {
        let t = vis.x - 1u;
        let a = positions[indices[3u * t]].xyz;
        let b = positions[indices[3u * t + 1u]].xyz;
        let c = positions[indices[3u * t + 2u]].xyz;
        let n = normalize(cross(b - a, c - a));
        let diffuse = max(dot(n, normalize(params.light_dir.xyz)), 0.0);
        let ambient = mix(vec3(0.10, 0.08, 0.07), vec3(0.18, 0.22, 0.30), n.y * 0.5 + 0.5);
        let albedo = vec3(0.85, 0.55, 0.30);
        color = albedo * (diffuse * vec3(1.0, 0.95, 0.85) + ambient);
    }
    let srgb = pow(clamp(color, vec3(0.0), vec3(1.0)), vec3(1.0 / 2.2));
    let rgba = vec4<u32>(vec3<u32>(round(srgb * 255.0)), 255u);
    image[i] = rgba.x | (rgba.y << 8u) | (rgba.z << 16u) | (rgba.w << 24u);
}
