//! A glTF writer for tests: scenes built in code (meshes, a node tree, cameras), written
//! as a `.glb`, so a test knows exactly what the loader must find and the renderer must
//! draw. Only what tests need: float positions, normals and UVs, vertex colours, u32
//! indices, TRS or matrix nodes, perspective and orthographic cameras.

use serde_json::Value;
/// For materials and damaged objects given as JSON, without a dependency of the caller's.
pub use serde_json::json;

/// One triangle primitive.
#[derive(Clone, Debug, Default)]
pub struct Primitive {
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Normals, one per position, or none.
    pub normals: Option<Vec<[f32; 3]>>,
    /// `TEXCOORD_0`, one per position, or none.
    pub uvs: Option<Vec<[f32; 2]>>,
    /// `COLOR_0`, one per position, or none.
    pub colors: Option<Colors>,
    /// Three per triangle.
    pub indices: Vec<u32>,
    /// Its material, an index the writer returned.
    pub material: Option<usize>,
}

/// A primitive's `COLOR_0`, in two of the forms glTF allows.
#[derive(Clone, Debug)]
pub enum Colors {
    /// VEC4 of normalized UNSIGNED_BYTE (what most exporters write).
    Rgba8(Vec<[u8; 4]>),
    /// VEC3 of FLOAT.
    RgbFloat(Vec<[f32; 3]>),
}

/// A node: what it places and where, relative to its parent.
#[derive(Clone, Debug, Default)]
pub struct Node {
    /// Its name, if any.
    pub name: Option<String>,
    /// The mesh it places.
    pub mesh: Option<usize>,
    /// The camera it carries.
    pub camera: Option<usize>,
    /// Its children's indices.
    pub children: Vec<usize>,
    /// Translation (TRS form).
    pub translation: Option<[f32; 3]>,
    /// Rotation as a quaternion x, y, z, w (TRS form).
    pub rotation: Option<[f32; 4]>,
    /// Scale (TRS form).
    pub scale: Option<[f32; 3]>,
    /// A column-major matrix instead of TRS.
    pub matrix: Option<[f32; 16]>,
}

/// A glTF document under construction, with its one binary buffer.
#[derive(Default)]
pub struct GltfWriter {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
    meshes: Vec<Value>,
    nodes: Vec<Value>,
    cameras: Vec<Value>,
    materials: Vec<Value>,
    images: Vec<Value>,
    textures: Vec<Value>,
    samplers: Vec<Value>,
    scene: Vec<usize>,
}

impl GltfWriter {
    /// An empty document.
    pub fn new() -> Self {
        Self::default()
    }

    /// Appends `bytes` as a buffer view and an accessor over it; returns the accessor.
    fn accessor(&mut self, bytes: &[u8], component: u32, kind: &str, count: usize) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.views.push(json!({
            "buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()
        }));
        self.bin.extend_from_slice(bytes);
        self.accessors.push(json!({
            "bufferView": self.views.len() - 1,
            "componentType": component,
            "count": count,
            "type": kind,
        }));
        self.accessors.len() - 1
    }

    /// Adds a mesh of `primitives`; returns its index.
    pub fn mesh(&mut self, name: &str, primitives: &[Primitive]) -> usize {
        const FLOAT: u32 = 5126;
        const UNSIGNED_INT: u32 = 5125;
        let mut out = Vec::new();
        for p in primitives {
            let position = self.accessor(
                bytemuck::cast_slice(&p.positions),
                FLOAT,
                "VEC3",
                p.positions.len(),
            );
            // POSITION must carry its bounds.
            let (mut min, mut max) = ([f32::MAX; 3], [f32::MIN; 3]);
            for v in &p.positions {
                for k in 0..3 {
                    min[k] = min[k].min(v[k]);
                    max[k] = max[k].max(v[k]);
                }
            }
            self.accessors[position]["min"] = json!(min);
            self.accessors[position]["max"] = json!(max);
            let mut attributes = json!({ "POSITION": position });
            if let Some(n) = &p.normals {
                attributes["NORMAL"] =
                    json!(self.accessor(bytemuck::cast_slice(n), FLOAT, "VEC3", n.len()));
            }
            if let Some(t) = &p.uvs {
                attributes["TEXCOORD_0"] =
                    json!(self.accessor(bytemuck::cast_slice(t), FLOAT, "VEC2", t.len()));
            }
            match &p.colors {
                Some(Colors::Rgba8(c)) => {
                    const UNSIGNED_BYTE: u32 = 5121;
                    let a = self.accessor(c.as_flattened(), UNSIGNED_BYTE, "VEC4", c.len());
                    self.accessors[a]["normalized"] = json!(true);
                    attributes["COLOR_0"] = json!(a);
                }
                Some(Colors::RgbFloat(c)) => {
                    attributes["COLOR_0"] =
                        json!(self.accessor(bytemuck::cast_slice(c), FLOAT, "VEC3", c.len()));
                }
                None => {}
            }
            let indices = self.accessor(
                bytemuck::cast_slice(&p.indices),
                UNSIGNED_INT,
                "SCALAR",
                p.indices.len(),
            );
            let mut primitive = json!({ "attributes": attributes, "indices": indices });
            if let Some(m) = p.material {
                primitive["material"] = json!(m);
            }
            out.push(primitive);
        }
        self.meshes.push(json!({ "name": name, "primitives": out }));
        self.meshes.len() - 1
    }

    /// Adds a perspective camera; returns its index.
    pub fn perspective_camera(&mut self, name: &str, yfov: f32, znear: f32) -> usize {
        self.cameras.push(json!({
            "name": name, "type": "perspective",
            "perspective": { "yfov": yfov, "znear": znear }
        }));
        self.cameras.len() - 1
    }

    /// Adds a camera given as its raw JSON object (for damaged ones).
    pub fn raw_camera(&mut self, camera: Value) -> usize {
        self.cameras.push(camera);
        self.cameras.len() - 1
    }

    /// Adds a material given as its JSON object (`pbrMetallicRoughness`, `alphaMode`,
    /// …, or damaged ones); returns its index.
    pub fn material(&mut self, material: Value) -> usize {
        self.materials.push(material);
        self.materials.len() - 1
    }

    /// Adds an image stored in the binary buffer (a buffer view) with its MIME type;
    /// returns the image's index.
    pub fn image_bytes(&mut self, bytes: &[u8], mime: &str) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.views.push(json!({
            "buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()
        }));
        self.bin.extend_from_slice(bytes);
        self.images
            .push(json!({ "bufferView": self.views.len() - 1, "mimeType": mime }));
        self.images.len() - 1
    }

    /// Adds an image given by `uri` (a file beside the model, or a `data:` URI);
    /// returns its index.
    pub fn image_uri(&mut self, uri: &str) -> usize {
        self.images.push(json!({ "uri": uri }));
        self.images.len() - 1
    }

    /// Adds a texture of `image`, with a sampler of its own when `sampler` is given (its
    /// JSON object: `wrapS`, `wrapT`, …); returns the texture's index.
    pub fn texture(&mut self, image: usize, sampler: Option<Value>) -> usize {
        let mut t = json!({ "source": image });
        if let Some(s) = sampler {
            self.samplers.push(s);
            t["sampler"] = json!(self.samplers.len() - 1);
        }
        self.textures.push(t);
        self.textures.len() - 1
    }

    /// Adds a node; returns its index.
    pub fn node(&mut self, node: Node) -> usize {
        let mut n = json!({});
        if let Some(name) = node.name {
            n["name"] = json!(name);
        }
        if let Some(m) = node.mesh {
            n["mesh"] = json!(m);
        }
        if let Some(c) = node.camera {
            n["camera"] = json!(c);
        }
        if !node.children.is_empty() {
            n["children"] = json!(node.children);
        }
        if let Some(t) = node.translation {
            n["translation"] = json!(t);
        }
        if let Some(r) = node.rotation {
            n["rotation"] = json!(r);
        }
        if let Some(s) = node.scale {
            n["scale"] = json!(s);
        }
        if let Some(m) = node.matrix {
            n["matrix"] = json!(m);
        }
        self.nodes.push(n);
        self.nodes.len() - 1
    }

    /// Makes `roots` the default scene's nodes.
    pub fn scene(&mut self, roots: &[usize]) {
        self.scene = roots.to_vec();
    }

    /// The JSON document, its buffer in the GLB's binary chunk.
    pub fn json(&self) -> Value {
        let mut root = json!({
            "asset": { "version": "2.0", "generator": "meshlight-testing" },
            "scene": 0,
            "scenes": [{ "nodes": self.scene }],
            "nodes": self.nodes,
            "meshes": self.meshes,
            "buffers": [{ "byteLength": self.padded_bin().len() }],
            "bufferViews": self.views,
            "accessors": self.accessors,
        });
        if !self.cameras.is_empty() {
            root["cameras"] = json!(self.cameras);
        }
        if !self.materials.is_empty() {
            root["materials"] = json!(self.materials);
        }
        for (key, list) in [
            ("images", &self.images),
            ("textures", &self.textures),
            ("samplers", &self.samplers),
        ] {
            if !list.is_empty() {
                root[key] = json!(list);
            }
        }
        root
    }

    fn padded_bin(&self) -> Vec<u8> {
        let mut bin = self.bin.clone();
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        bin
    }

    /// The document as a `.glb` file's bytes.
    pub fn glb(&self) -> Vec<u8> {
        glb_container(&self.json().to_string(), &self.padded_bin())
    }
}

/// A GLB file: the 12-byte header, `json` as the JSON chunk (padded with spaces, as the
/// format wants every chunk a multiple of 4 bytes) and `bin` as the binary chunk (padded
/// with zeros).
pub fn glb_container(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut json = json.as_bytes().to_vec();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut bin = bin.to_vec();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let mut glb = Vec::new();
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&((12 + 8 + json.len() + 8 + bin.len()) as u32).to_le_bytes());
    glb.extend_from_slice(&(json.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&json);
    glb.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"BIN\0");
    glb.extend_from_slice(&bin);
    glb
}

/// `rgba` (`width × height` pixels, rows top to bottom) as a PNG file's bytes.
pub fn png_bytes(width: u32, height: u32, rgba: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, width, height);
    encoder.set_color(png::ColorType::Rgba);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().expect("PNG header");
    writer.write_image_data(rgba).expect("PNG data");
    writer.finish().expect("PNG end");
    out
}

/// `rgb` (`width × height` pixels) as a JPEG file's bytes at `quality` (1 to 100).
pub fn jpeg_bytes(width: u16, height: u16, rgb: &[u8], quality: u8) -> Vec<u8> {
    let mut out = Vec::new();
    jpeg_encoder::Encoder::new(&mut out, quality)
        .encode(rgb, width, height, jpeg_encoder::ColorType::Rgb)
        .expect("JPEG encoding");
    out
}
