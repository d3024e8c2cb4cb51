//! Layouts read from the shader (`BindingLayout::from_shader`): WGSL globals named like
//! slots and scratch resources bind them, uniforms take the bytes given under their name,
//! and every mismatch is an error naming the file, the variable and the slot (lavapipe
//! in CI).

mod support;

use meshlight_graph::*;
use support::gpu;

const N: u32 = 64;

/// A shader of these tests, written inline: `label` ends its file path in parentheses,
/// which every error about the shader quotes, so each test can tell its shader's errors.
macro_rules! reflect_shader {
    ($name:literal, $label:literal, $source:literal) => {
        PassShader {
            name: concat!("test::reflect_", $name),
            source: $source,
            file_path: concat!("graph/tests/bindings_from_shader.rs (", $label, ")"),
            modules: &[],
        }
    };
}

const GOOD: PassShader = reflect_shader!(
    "good",
    "good",
    "
struct Params { scale: u32, add: u32, _a: u32, _b: u32 }
@group(0) @binding(0) var<storage, read> input: array<u32>;
@group(0) @binding(1) var<storage, read_write> output: array<u32>;
@group(0) @binding(5) var<uniform> params: Params;
@group(0) @binding(7) var<storage, read_write> words: array<u32>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&output) { return; }
    words[i] = input[i] * params.scale;
    output[i] = words[i] + params.add;
}
"
);

/// `main` copies; only `scaled`, another entry point, reads the uniform.
const COPY_BESIDE_SCALED: PassShader = reflect_shader!(
    "copy_beside_scaled",
    "copy beside scaled",
    "
struct Params { scale: u32, add: u32, _a: u32, _b: u32 }
@group(0) @binding(0) var<storage, read> input: array<u32>;
@group(0) @binding(1) var<storage, read_write> output: array<u32>;
@group(0) @binding(5) var<uniform> params: Params;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < arrayLength(&output) { output[id.x] = input[id.x]; }
}
@compute @workgroup_size(64)
fn scaled(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < arrayLength(&output) { output[id.x] = input[id.x] * params.scale; }
}
"
);

/// A variable named after nothing the pass has.
const STRAY: PassShader = reflect_shader!(
    "stray",
    "stray",
    "
@group(0) @binding(0) var<storage, read> input: array<u32>;
@group(0) @binding(1) var<storage, read_write> output: array<u32>;
@group(0) @binding(2) var<storage, read> stray: array<u32>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    output[id.x] = input[id.x] + stray[id.x];
}
"
);

/// Writes the slot the contract only reads.
const WRITES_INPUT: PassShader = reflect_shader!(
    "writes_input",
    "writes input",
    "
@group(0) @binding(0) var<storage, read_write> input: array<u32>;
@group(0) @binding(1) var<storage, read_write> output: array<u32>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    input[id.x] = 1u;
    output[id.x] = input[id.x];
}
"
);

/// Reads the slot's u32 elements as vec2<u32>.
const WIDE: PassShader = reflect_shader!(
    "wide",
    "wide",
    "
@group(0) @binding(0) var<storage, read> input: array<vec2<u32>>;
@group(0) @binding(1) var<storage, read_write> output: array<u32>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    output[id.x] = input[id.x].x;
}
"
);

struct Reflected {
    shader: &'static PassShader,
    /// The layout of group 0: read from the shader, maybe with explicit entries.
    layout: BindingLayout,
    /// The name the pass gives the uniform bytes under; `None` gives none.
    uniform: Option<&'static str>,
}

impl Reflected {
    /// `shader` with its layout read from it and the bytes given as `params`.
    fn new(shader: &'static PassShader) -> Self {
        Self {
            shader,
            layout: BindingLayout::from_shader("scale"),
            uniform: Some("params"),
        }
    }
}

impl Pass for Reflected {
    fn implementation(&self) -> Implementation {
        Implementation::new(
            "reflected", // The arithmetic passes' `input` and `output`, under a stage name of its own.
            StageContract {
                stage: "scale",
                slots: support::transform_contract().slots,
            },
        )
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        support::scratch_words(ctx, N);
        ctx.program(
            "main",
            ProgramDesc::compute(self.shader, "main").layout(self.layout.clone()),
        );
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        let params = [3u32, 7, 0, 0];
        let uniforms: Vec<(&str, &[u8])> = self
            .uniform
            .map(|name| (name, bytemuck::cast_slice(&params)))
            .into_iter()
            .collect();
        support::dispatch_once(ctx, "main", &uniforms, [N.div_ceil(64), 1, 1])
    }
}

/// Runs the pass with `shader` once; the output, or the error.
fn run(shader: &'static PassShader) -> std::result::Result<Vec<u32>, GraphError> {
    run_pass(Reflected::new(shader))
}

/// Runs `pass` once; the output, or the error.
fn run_pass(pass: Reflected) -> std::result::Result<Vec<u32>, GraphError> {
    let gpu = gpu();
    let input: Vec<u32> = (0..N).collect();
    let mut g = GraphBuilder::new();
    let input_handle = g.import_buffer(
        "input",
        BufferDesc::array(Element::U32, N as u64),
        wgpu::BufferUsages::STORAGE,
    );
    let output = g.create_buffer("output", BufferDesc::array(Element::U32, N as u64));
    let out = g.add_pass(
        "scale",
        pass,
        Bindings::new()
            .bind("input", input_handle)
            .bind("output", output),
    )?;
    g.export(out.buffer("output").unwrap());
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu))?;
    let buffer = gpu.buffer_with_data(
        "input",
        bytemuck::cast_slice(&input),
        wgpu::BufferUsages::STORAGE,
    );
    let mut exec = Executor::new(gpu);
    exec.execute(&compiled, &Imports::new().buffer("input", &buffer))?;
    Ok(bytemuck::pod_collect_to_vec(&exec.read_buffer("output")?))
}

/// Runs `shader` expecting an error whose message contains every one of `parts`.
fn assert_error_names(shader: &'static PassShader, parts: &[&str]) {
    assert_contains(&error_of(shader), parts);
}

fn error_of(shader: &'static PassShader) -> String {
    pass_error(Reflected::new(shader))
}

fn pass_error(pass: Reflected) -> String {
    let name = pass.shader.name;
    match run_pass(pass) {
        Err(e) => e.to_string(),
        Ok(out) => panic!("{name} ran: {out:?}"),
    }
}

/// Asserts that `message` contains every one of `parts`.
fn assert_contains(message: &str, parts: &[&str]) {
    for part in parts {
        assert!(message.contains(part), "`{part}` missing from: {message}");
    }
}

#[test]
fn slots_scratch_and_uniforms_bind_by_their_names_in_the_shader() {
    let out = run(&GOOD).unwrap_or_else(|e| panic!("{e}"));
    let want: Vec<u32> = (0..N).map(|i| i * 3 + 7).collect();
    assert_eq!(out, want);
}

#[test]
fn a_variable_that_matches_nothing_is_named_with_what_it_could_be() {
    assert_error_names(
        &STRAY,
        &[
            "(stray)",
            "`stray`",
            "matches no slot of stage `scale` (input, output)",
            "no scratch resource (words)",
        ],
    );
}

#[test]
fn writing_a_read_only_slot_is_an_error_naming_the_slot() {
    assert_error_names(
        &WRITES_INPUT,
        &[
            "(writes input)",
            "slot `input` is storage-read",
            "declares it writable",
        ],
    );
}

#[test]
fn an_element_size_unlike_the_slots_is_an_error_naming_both_sizes() {
    assert_error_names(
        &WIDE,
        &[
            "(wide)",
            "slot `input` holds elements of 4 bytes",
            "8-byte elements",
        ],
    );
}

#[test]
fn a_uniform_given_under_a_name_the_shader_lacks_is_an_error_listing_its_uniforms() {
    let e = pass_error(Reflected {
        uniform: Some("param"),
        ..Reflected::new(&GOOD)
    });
    assert_contains(&e, &["no uniform `param`", "uniforms of group 0: params"]);
}

#[test]
fn a_uniform_given_no_bytes_is_an_error_naming_it() {
    let e = pass_error(Reflected {
        uniform: None,
        ..Reflected::new(&GOOD)
    });
    assert_contains(
        &e,
        &[
            "uniform `params` (binding 5)",
            "given no bytes",
            "uniforms of group 0: params",
        ],
    );
}

#[test]
fn a_layout_naming_a_uniform_unlike_its_variable_is_an_error_naming_both() {
    let e = pass_error(Reflected {
        layout: BindingLayout::from_shader("scale").uniform(5, "settings"),
        uniform: Some("settings"),
        ..Reflected::new(&GOOD)
    });
    assert_contains(
        &e,
        &["(good)", "`settings`", "the shader calls it `params`"],
    );
}

#[test]
fn a_uniform_only_another_entry_point_uses_may_be_given_but_a_misspelt_one_may_not() {
    let out = run(&COPY_BESIDE_SCALED).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(out, (0..N).collect::<Vec<u32>>());
    let e = pass_error(Reflected {
        uniform: Some("param"),
        ..Reflected::new(&COPY_BESIDE_SCALED)
    });
    assert_contains(&e, &["no uniform `param`", "uniforms of group 0: params"]);
}
