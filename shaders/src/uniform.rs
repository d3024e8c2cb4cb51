//! A pass's uniform block, declared once for both sides of the upload.
//!
//! A pass fills a `#[repr(C)]` struct in Rust and its shaders read a WGSL struct of the
//! same fields. Written twice, the two drift apart one field at a time; [`uniform_block!`]
//! writes the Rust struct and the WGSL struct (as a crate-local module the shaders
//! import) from one list of fields, and checks at compile time that every field sits where
//! WGSL's layout rules put it.

/// Declares a uniform block: a Pod Rust struct, and a crate-local WGSL module holding the
/// struct of the same fields, for [`crate::pass_shader!`]'s `params:` argument.
///
/// Field types are the Rust types of the upload; each stands for one WGSL type:
/// `u32`, `i32`, `f32`, `[u32; 2]` (`vec2<u32>`), `[u32; 4]` (`vec4<u32>`), `[f32; 2]`,
/// `[f32; 4]` and `[[f32; 4]; 4]` (`mat4x4<f32>`). Padding is written as scalar fields
/// (`pad_a: u32`): an array or `vec3` there would change the WGSL alignment. Names may
/// neither begin with `_` nor end in a digit, which naga_oil refuses in a module. A field
/// whose offset is not a multiple of its WGSL alignment fails to compile, as does a block
/// whose size is not a multiple of 16 bytes (so WGSL's size of the struct is Rust's).
///
/// ```
/// meshlight_shaders::uniform_block! {
///     /// The uniform of a pass that scales its input.
///     struct GpuParams as "Params" in "scale::params" {
///         /// Values to scale.
///         count: u32,
///         factor: f32,
///         pad_a: u32,
///         pad_b: u32,
///     }
/// }
/// assert_eq!(std::mem::size_of::<GpuParams>(), 16);
/// assert!(GpuParams::MODULE.source.contains("struct Params {\n    count: u32,\n    factor: f32,"));
/// ```
#[macro_export]
macro_rules! uniform_block {
    (
        $(#[$meta:meta])*
        $vis:vis struct $rust:ident as $wgsl:literal in $module:literal {
            $( $(#[$field_meta:meta])* $field_vis:vis $field:ident : $ty:tt ),* $(,)?
        }
    ) => {
        $(#[$meta])*
        #[repr(C)]
        #[derive(Clone, Copy, Debug, Default, PartialEq, ::bytemuck::Pod, ::bytemuck::Zeroable)]
        $vis struct $rust {
            $( $(#[$field_meta])* $field_vis $field: $ty, )*
        }

        impl $rust {
            /// The WGSL module declaring this block's struct, for the shaders that read it.
            #[allow(dead_code)]
            pub const MODULE: $crate::LocalModule = $crate::LocalModule {
                name: $module,
                source: concat!(
                    "#define_import_path ", $module, "\n\nstruct ", $wgsl, " {\n",
                    $( "    ", stringify!($field), ": ", $crate::uniform_wgsl_type!($ty), ",\n", )*
                    "}\n"
                ),
                file_path: concat!(file!(), " (uniform_block ", stringify!($rust), ")"),
            };
        }

        const _: () = {
            $( assert!(
                ::core::mem::offset_of!($rust, $field) % $crate::uniform_wgsl_align!($ty) == 0,
                concat!("uniform_block ", stringify!($rust), ": `", stringify!($field),
                    "` is not at a multiple of its WGSL alignment; move it or pad before it")
            ); )*
            assert!(
                ::core::mem::size_of::<$rust>() % 16 == 0,
                concat!("uniform_block ", stringify!($rust),
                    ": the block is not whole 16-byte rows; pad it to a multiple of 16 bytes")
            );
        };
    };
}

/// The WGSL type a [`uniform_block!`] field of this Rust type declares.
#[doc(hidden)]
#[macro_export]
macro_rules! uniform_wgsl_type {
    (u32) => {
        "u32"
    };
    (i32) => {
        "i32"
    };
    (f32) => {
        "f32"
    };
    ([u32; 2]) => {
        "vec2<u32>"
    };
    ([u32; 4]) => {
        "vec4<u32>"
    };
    ([f32; 2]) => {
        "vec2<f32>"
    };
    ([f32; 4]) => {
        "vec4<f32>"
    };
    ([[f32; 4]; 4]) => {
        "mat4x4<f32>"
    };
}

/// The WGSL alignment of a [`uniform_block!`] field of this Rust type.
#[doc(hidden)]
#[macro_export]
macro_rules! uniform_wgsl_align {
    (u32) => {
        4
    };
    (i32) => {
        4
    };
    (f32) => {
        4
    };
    ([u32; 2]) => {
        8
    };
    ([f32; 2]) => {
        8
    };
    ([u32; 4]) => {
        16
    };
    ([f32; 4]) => {
        16
    };
    ([[f32; 4]; 4]) => {
        16
    };
}
