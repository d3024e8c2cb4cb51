// Clears the `texture` implementation's R64Uint visibility texture to 0 (empty) with
// plain stores: wgpu clears a texture that cannot be a render target by copying zeros
// from a buffer, which costs far more than this dispatch.

@group(0) @binding(0) var visbuffer: texture_storage_2d<r64uint, write>;

@compute @workgroup_size(16, 16)
fn clear(@builtin(global_invocation_id) id: vec3<u32>) {
    if all(id.xy < textureDimensions(visbuffer)) {
        textureStore(visbuffer, id.xy, vec4(0lu));
    }
}
