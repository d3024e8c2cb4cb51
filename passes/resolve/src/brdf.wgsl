#define_import_path resolve::brdf

// glTF's metallic-roughness model: Lambert diffuse and GGX specular (Trowbridge-Reitz
// distribution, height-correlated Smith visibility, Schlick Fresnel). `cpu::brdf` is the
// reference, operation for operation.
//
// Lights are given as the colour a white Lambert surface facing them reflects (the
// flat shading this replaced), so a light of colour c adds
// `(diffuse + π · specular_brdf) · c · n·l`.

const PI: f32 = 3.14159265358979;
// The reflectance at normal incidence of every dielectric (4%, glTF's choice).
const DIELECTRIC_SPECULAR: f32 = 0.04;
// Smallest GGX alpha: a perfect mirror's highlight is a point no pixel samples.
const MIN_ALPHA: f32 = 0.002;

struct Surface {
    // Diffuse albedo: the base colour of the non-metallic part.
    diffuse: vec3<f32>,
    // Specular reflectance at normal incidence.
    specular: vec3<f32>,
    // GGX alpha: roughness squared.
    alpha: f32,
}

fn surface(base: vec3<f32>, metallic: f32, roughness: f32) -> Surface {
    var s: Surface;
    s.diffuse = base * (1.0 - metallic);
    s.specular = mix(vec3(DIELECTRIC_SPECULAR), base, metallic);
    s.alpha = max(roughness * roughness, MIN_ALPHA);
    return s;
}

// What a light of unit colour from direction `l` adds towards the eye at `v` (all unit
// vectors, world space).
fn light_response(s: Surface, n: vec3<f32>, v: vec3<f32>, l: vec3<f32>) -> vec3<f32> {
    let nl = dot(n, l);
    if nl <= 0.0 {
        return vec3(0.0);
    }
    let nv = max(dot(n, v), 1e-4);
    let h = normalize(v + l);
    let nh = max(dot(n, h), 0.0);
    let vh = max(dot(v, h), 0.0);
    let a2 = s.alpha * s.alpha;
    let q = nh * nh * (a2 - 1.0) + 1.0;
    let d = a2 / (PI * q * q);
    let vis = 0.5 / (nl * sqrt(nv * nv * (1.0 - a2) + a2) + nv * sqrt(nl * nl * (1.0 - a2) + a2));
    let f = s.specular + (vec3(1.0) - s.specular) * pow(1.0 - vh, 5.0);
    return (s.diffuse + PI * d * vis * f) * nl;
}

// What a uniform ambient light of unit colour adds: the diffuse albedo, and the
// specular reflectance as if the sky were mirrored evenly.
fn ambient_response(s: Surface) -> vec3<f32> {
    return s.diffuse + s.specular;
}
