//! Pipeline files as untrusted input: zero extents and unknown usages are typed errors
//! naming the resource, and only regular files under the size limit are read.

use meshlight_graph::GraphError;
use meshlight_graph::file::{
    MAX_PIPELINE_FILE_BYTES, Pipeline, Registry, ResourceProblem, SourceProblem, load_pipeline,
    parse_pipeline, read_pipeline_text,
};
use std::path::{Path, PathBuf};

const TEXTURE: &str = r#"
[params]
width = 8
height = 4

[[resource]]
name = "image"
kind = "KIND"
texture = { format = "rgba8unorm", SIZE }
USAGE
"#;

fn texture_file(kind: &str, size: &str, usage: &str) -> String {
    TEXTURE
        .replace("KIND", kind)
        .replace("SIZE", size)
        .replace("USAGE", usage)
}

/// The problem of the error for resource `image`, or a panic naming what came instead.
fn resource_problem(result: meshlight_graph::Result<impl Sized>) -> ResourceProblem {
    match result.map(|_| ()) {
        Err(GraphError::PipelineResource {
            file,
            resource,
            problem,
        }) => {
            assert_eq!((file.as_str(), resource.as_str()), ("t.toml", "image"));
            problem
        }
        other => panic!("expected a typed resource error, got {other:?}"),
    }
}

#[test]
fn a_texture_with_a_zero_dimension_is_refused_naming_it() {
    let registry = Registry::new();
    let fine = texture_file("transient", "width = 8, height = 4", "");
    assert!(parse_pipeline(&fine, "t.toml", &registry).is_ok());
    for (size, expected) in [
        ("width = 0, height = 0", (0, 0, 1, 1)),
        ("width = 8, height = 0", (8, 0, 1, 1)),
        ("width = 8, height = 4, mip_levels = 0", (8, 4, 0, 1)),
        ("width = 8, height = 4, layers = 0", (8, 4, 1, 0)),
    ] {
        for kind in ["transient", "exported", "imported", "history"] {
            let text = texture_file(kind, size, "");
            match resource_problem(parse_pipeline(&text, "t.toml", &registry)) {
                ResourceProblem::ZeroExtent {
                    what,
                    width,
                    height,
                    mip_levels,
                    layers,
                } => {
                    assert_eq!(what, "texture");
                    assert_eq!((width, height, mip_levels, layers), expected, "{size}");
                }
                other => panic!("{size}: {other:?}"),
            }
        }
    }
    // Through a parameter, set by the file or by the caller.
    let by_param = texture_file(
        "transient",
        "width_param = \"width\", height_param = \"height\"",
        "",
    );
    assert!(parse_pipeline(&by_param, "t.toml", &registry).is_ok());
    let mut zero = Pipeline::parse(&by_param, "t.toml").unwrap();
    zero.set_param("height", 0).unwrap();
    let e = zero.build(&registry).err();
    assert!(
        matches!(
            e,
            Some(GraphError::PipelineResource {
                problem: ResourceProblem::ZeroExtent {
                    width: 8,
                    height: 0,
                    ..
                },
                ..
            })
        ),
        "{e:?}"
    );
    let written = by_param.replace("width = 8", "width = 0");
    assert!(matches!(
        resource_problem(parse_pipeline(&written, "t.toml", &registry)),
        ResourceProblem::ZeroExtent { width: 0, .. }
    ));
    let message = parse_pipeline(&written, "t.toml", &registry)
        .err()
        .unwrap()
        .to_string();
    assert!(
        message.contains("`image`") && message.contains("0 × 4"),
        "{message}"
    );
}

#[test]
fn a_visibility_target_with_a_zero_side_is_refused_naming_it() {
    let text = "[[resource]]\nname = \"image\"\nkind = \"transient\"\nvisibility = { width = 0, height = 16 }\n";
    match resource_problem(parse_pipeline(text, "t.toml", &Registry::new())) {
        ResourceProblem::ZeroExtent { what, width, .. } => {
            assert_eq!((what, width), ("visibility target", 0))
        }
        other => panic!("{other:?}"),
    }
    let fine = text.replace("width = 0", "width = 16");
    assert!(parse_pipeline(&fine, "t.toml", &Registry::new()).is_ok());
}

#[test]
fn a_buffer_of_zero_bytes_written_in_the_file_is_refused_naming_it() {
    let buffer = |fields: &str| {
        format!(
            "[params]\nn = 0\n[[resource]]\nname = \"image\"\nkind = \"transient\"\nbuffer = {{ {fields} }}\n"
        )
    };
    let registry = Registry::new();
    for (fields, count, element_size) in [
        ("element = \"u32\", count = 0", Some(0), 4),
        (
            "element = \"blob\", element_size = 0, count = 8",
            Some(8),
            0,
        ),
        (
            "element = \"blob\", element_size = 0, count_param = \"n\"",
            None,
            0,
        ),
    ] {
        assert_eq!(
            resource_problem(parse_pipeline(&buffer(fields), "t.toml", &registry)),
            ResourceProblem::EmptyBuffer {
                count,
                element_size
            },
            "{fields}"
        );
    }
    // A parameter may be 0 until the caller sets it: checked where it is resolved.
    let by_param = buffer("element = \"u32\", count_param = \"n\"");
    assert!(parse_pipeline(&by_param, "t.toml", &registry).is_ok());
    let fine = buffer("element = \"u32\", count = 1");
    assert!(parse_pipeline(&fine, "t.toml", &registry).is_ok());
}

#[test]
fn an_unknown_usage_is_refused_on_every_kind_of_resource() {
    let registry = Registry::new();
    let size = "width = 8, height = 4";
    for kind in ["transient", "exported", "imported", "history"] {
        let known = texture_file(kind, size, "usage = [\"STORAGE_BINDING\", \"COPY_SRC\"]");
        assert!(
            parse_pipeline(&known, "t.toml", &registry).is_ok(),
            "{kind}"
        );
        let texture = texture_file(kind, size, "usage = [\"COPY_SRC\", \"STORAGE\"]");
        let buffer = format!(
            "[[resource]]\nname = \"image\"\nkind = \"{kind}\"\nbuffer = {{ element = \"u32\", count = 4 }}\nusage = [\"STORAGE\", \"storage\"]\n"
        );
        // The unknown name, and two of the known ones the error must list.
        for (text, want_kind, want_usage, listed) in [
            (
                texture,
                "texture",
                "STORAGE",
                ["STORAGE_BINDING", "RENDER_ATTACHMENT"],
            ),
            (buffer, "buffer", "storage", ["STORAGE", "INDIRECT"]),
        ] {
            match resource_problem(parse_pipeline(&text, "t.toml", &registry)) {
                ResourceProblem::UnknownUsage { kind, usage, known } => {
                    assert_eq!((kind, usage.as_str()), (want_kind, want_usage));
                    assert!(listed.iter().all(|n| known.contains(n)), "{known}");
                }
                other => panic!("{kind}: {other:?}"),
            }
        }
    }
    let visibility = "[[resource]]\nname = \"image\"\nkind = \"transient\"\nvisibility = { width = 4, height = 4 }\nusage = [\"SAMPLED\"]\n";
    assert!(matches!(
        resource_problem(parse_pipeline(visibility, "t.toml", &registry)),
        ResourceProblem::UnknownUsage { usage, .. } if usage == "SAMPLED"
    ));
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "meshlight-pipeline-inputs-{}-{name}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn source_problem(path: &Path) -> SourceProblem {
    match read_pipeline_text(path) {
        Err(GraphError::PipelineSource { file, problem }) => {
            assert_eq!(file, path.display().to_string());
            problem
        }
        other => panic!(
            "{}: expected a typed source error, got {other:?}",
            path.display()
        ),
    }
}

#[test]
fn only_regular_files_under_the_size_limit_are_read() {
    // A device is refused from its metadata: reading /dev/zero would never end.
    assert_eq!(
        source_problem(Path::new("/dev/zero")),
        SourceProblem::NotARegularFile {
            what: "a character device"
        }
    );
    assert!(matches!(
        load_pipeline(Path::new("/dev/zero"), &Registry::new()),
        Err(GraphError::PipelineSource {
            problem: SourceProblem::NotARegularFile { .. },
            ..
        })
    ));
    let dir = scratch("limits");
    assert_eq!(
        source_problem(&dir),
        SourceProblem::NotARegularFile {
            what: "a directory"
        }
    );
    // One byte over the limit (a sparse file: nothing is written).
    let big = dir.join("big.toml");
    let f = std::fs::File::create(&big).unwrap();
    f.set_len(MAX_PIPELINE_FILE_BYTES + 1).unwrap();
    assert_eq!(
        source_problem(&big),
        SourceProblem::TooLarge {
            bytes: MAX_PIPELINE_FILE_BYTES + 1,
            limit: MAX_PIPELINE_FILE_BYTES
        }
    );
    f.set_len(MAX_PIPELINE_FILE_BYTES).unwrap();
    assert!(
        read_pipeline_text(&big).is_ok(),
        "a file at the limit is read"
    );
    assert!(matches!(
        source_problem(&dir.join("missing.toml")),
        SourceProblem::Unreadable { .. }
    ));
    let binary = dir.join("binary.toml");
    std::fs::write(&binary, [b'a', 0xff, 0xfe]).unwrap();
    assert!(matches!(
        source_problem(&binary),
        SourceProblem::Unreadable { reason } if reason.contains("UTF-8")
    ));
    let shipped = concat!(env!("CARGO_MANIFEST_DIR"), "/../pipelines/prefix_sum.toml");
    assert!(
        read_pipeline_text(Path::new(shipped))
            .unwrap()
            .contains("[[pass]]")
    );
    let _ = std::fs::remove_dir_all(&dir);
}
