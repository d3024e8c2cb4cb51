#define_import_path resolve::visibility

// The visibility buffer as both resolve shaders read it (depth.wgsl per fragment,
// shade.wgsl per pixel), and the cluster slots its ids index.

#import meshlight::meshlet::Cluster

#ifdef VIS_TEXTURE
// The software rasteriser's `texture` target: an R64Uint storage texture.
@group(0) @binding(0) var visbuffer: texture_storage_2d<r64uint, read>;
#else
// width × height values in the pair form (low word, high word), so reading them needs
// no 64-bit integers.
@group(0) @binding(0) var<storage, read> visbuffer: array<vec2<u32>>;
#endif
@group(0) @binding(1) var<storage, read> raster_clusters: array<Cluster>;

// The value at `pixel` of an image `width` pixels wide, in the pair form.
fn visibility_at(pixel: vec2<u32>, width: u32) -> vec2<u32> {
#ifdef VIS_TEXTURE
    let v = textureLoad(visbuffer, pixel).x;
    return vec2(u32(v & 0xfffffffflu), u32(v >> 32u));
#else
    return visbuffer[pixel.y * width + pixel.x];
#endif
}
