//! The WGSL and its Rust twins are mirrored by name: every function of the
//! shaders, as naga parses the assembled kernels, has a Rust function of the
//! same name in its twin file (or folder), so a reader who finds one finds
//! the other. A WGSL function may also be mirrored by
//! - a method: `trig_at` by `Trig::at` (WGSL has no methods; the type's
//!   name in snake case, then the method's);
//! - a closure bound by `let`: `ar1` by `let ar1 = |..|` in `draw_noise`.
//!
//! Where there is no twin, [`EXCEPTIONS`] says why; an exception that is no
//! longer needed fails too. The GPU backend and the CPU backend never import
//! from each other: what both need lives in a neutral module of the engine.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use stickslip::engine::gpu::source::{check_wgsl, ensemble_wgsl};

/// Each shader and its Rust twin: files, or folders whose `.rs` files all
/// count.
const TWINS: &[(&str, &[&str])] = &[
    ("rng.wgsl", &["src/engine/rng.rs"]),
    ("effects.wgsl", &["src/engine/cpu/effects.rs"]),
    ("oscillator.wgsl", &["src/engine/cpu/oscillator"]),
    ("reduce.wgsl", &["src/engine/reduce.rs"]),
    ("ensemble.wgsl", &["src/engine/gpu/ensemble.rs", "src/engine/gpu/shared.rs"]),
    ("check.wgsl", &["src/engine/gpu/check.rs"]),
];

/// WGSL functions without a Rust function of the same name in their twin:
/// (shader, function, the Rust file that holds a twin of that name
/// elsewhere, or none, and why).
const EXCEPTIONS: &[(&str, &str, Option<&str>, &str)] = &[
    (
        "effects.wgsl",
        "drift_factor",
        Some("src/engine/effects/tables.rs"),
        "beside the drift forms it defines: the model scales N0 by the drift's mean over a window",
    ),
    (
        "effects.wgsl",
        "harmonic_term",
        None,
        "the kernel takes a cos per harmonic; the CPU sums the harmonics by angle addition in `harmonics_n` \
         (the difference table in `src/engine/cpu/oscillator/mod.rs`)",
    ),
    (
        "oscillator.wgsl",
        "memory_form",
        Some("src/engine/effects/params.rs"),
        "`Memory::form`, beside the flattened effects it reads: the GPU host specialises the kernel by it too",
    ),
    ("reduce.wgsl", "is_non_finite", None, "Rust has `f32::is_finite`; WGSL has no isnan or isinf"),
    (
        "reduce.wgsl",
        "order_key",
        None,
        "a peak's f32 as a u32 that atomicMax can order (WGSL has no atomic float max); the CPU keeps the \
         extremes as floats (`widest`), and the GPU host decodes the keys (`from_order_key` in ensemble.rs)",
    ),
    ("reduce.wgsl", "add_u64", None, "WGSL has no 64-bit integers, so sums carry in u32 words; Rust adds u64"),
    ("reduce.wgsl", "add_u96", None, "the 96-bit sum of squares in u32 words; Rust adds u128"),
    (
        "reduce.wgsl",
        "atomic_add_u64",
        None,
        "a GPU point's invocations add to its accumulator at once, with atomics; the CPU reduces in order",
    ),
    ("reduce.wgsl", "atomic_add_u96", None, "as atomic_add_u64, for the 96-bit sum of squares"),
    (
        "reduce.wgsl",
        "flush_tally",
        None,
        "an invocation tallies its periods privately, then adds them to the point's accumulator once; the CPU \
         adds a whole path (`PointAccumulator::add_path`)",
    ),
    (
        "ensemble.wgsl",
        "record_sample",
        None,
        "writes a noise-aligned sample into the samples buffer; the CPU's samplers keep theirs in memory \
         (`Sampler::push`)",
    ),
    (
        "ensemble.wgsl",
        "load_invocation",
        None,
        "which point and realisation an invocation runs, and its path state from the paths buffer; a CPU path \
         stays in memory",
    ),
    ("ensemble.wgsl", "store_path", None, "writes the path state back to its buffer between dispatches"),
    ("ensemble.wgsl", "init_paths", None, "an entry point: starts every path (the CPU's `Path::new`)"),
    ("ensemble.wgsl", "run_cycles", None, "an entry point: one dispatch's periods (the CPU's `simulate_paths`)"),
];

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The `.rs` files of a twin entry: the file, or every file in the folder.
fn rust_files(entry: &str) -> Vec<PathBuf> {
    let path = root().join(entry);
    if path.is_dir() {
        let mut files: Vec<PathBuf> = std::fs::read_dir(&path)
            .unwrap_or_else(|e| panic!("{entry}: {e}"))
            .map(|e| e.expect("a folder entry").path())
            .filter(|p| p.extension().is_some_and(|x| x == "rs"))
            .collect();
        files.sort();
        files
    } else {
        assert!(path.is_file(), "the Rust twin {entry} does not exist");
        vec![path]
    }
}

/// The identifier at the start of `text`.
fn ident(text: &str) -> &str {
    let end = text.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).unwrap_or(text.len());
    &text[..end]
}

/// `PeakRange` -> `peak_range`.
fn snake(name: &str) -> String {
    let mut out = String::new();
    for (i, c) in name.chars().enumerate() {
        if c.is_ascii_uppercase() {
            if i > 0 {
                out.push('_');
            }
            out.push(c.to_ascii_lowercase());
        } else {
            out.push(c);
        }
    }
    out
}

/// The names a Rust file mirrors WGSL functions by: its functions and
/// methods, each method also as `type_method`, and closures bound by `let`.
fn rust_names(source: &str) -> BTreeSet<String> {
    let mut names = BTreeSet::new();
    let mut impl_type: Option<String> = None;
    for line in source.lines() {
        let code = line.split("//").next().unwrap_or("");
        if let Some(rest) = code.strip_prefix("impl") {
            // `impl<'a> Path<'a> {`, `impl Trait for Type {`: the type is the
            // last path before the brace, generics dropped.
            let head = rest.trim_end().trim_end_matches('{').trim();
            let head = head.rsplit(" for ").next().unwrap_or(head);
            let head = if head.starts_with('<') { head.split_once('>').map_or(head, |(_, t)| t) } else { head };
            impl_type = Some(ident(head.trim().rsplit("::").next().unwrap_or("")).to_string());
        } else if code == "}" {
            impl_type = None;
        }
        for (at, _) in code.match_indices("fn ") {
            if at > 0 && code[..at].ends_with(|c: char| c.is_ascii_alphanumeric() || c == '_') {
                continue;
            }
            let name = ident(&code[at + 3..]);
            if name.is_empty() {
                continue;
            }
            names.insert(name.to_string());
            if let Some(t) = impl_type.as_deref().filter(|_| code.starts_with("    ")) {
                names.insert(format!("{}_{name}", snake(t)));
            }
        }
        if let Some((_, rest)) = code.split_once("let ") {
            let name = ident(rest);
            let after = rest[name.len()..].trim_start();
            if let Some(value) = after.strip_prefix('=')
                && matches!(value.trim_start().chars().next(), Some('|'))
            {
                names.insert(name.to_string());
            }
        }
    }
    names
}

/// Every function of the assembled kernels (helpers and entry points), by
/// the shader file that defines it.
fn wgsl_functions() -> Vec<(String, String)> {
    let mut names = BTreeSet::new();
    for source in [ensemble_wgsl(), check_wgsl()] {
        let module = naga::front::wgsl::parse_str(&source).expect("the kernel parses");
        names.extend(module.functions.iter().filter_map(|(_, f)| f.name.clone()));
        names.extend(module.entry_points.iter().map(|e| e.name.clone()));
    }
    let shaders: Vec<(String, String)> =
        TWINS.iter().map(|(shader, _)| (shader.to_string(), read(&root().join("shaders").join(shader)))).collect();
    names
        .into_iter()
        .map(|name| {
            let defines = |text: &str| text.lines().any(|l| l.starts_with(&format!("fn {name}(")));
            let files: Vec<&String> = shaders.iter().filter(|(_, text)| defines(text)).map(|(s, _)| s).collect();
            assert_eq!(files.len(), 1, "the WGSL function `{name}` is defined in {files:?}, not in one shader file");
            (files[0].clone(), name)
        })
        .collect()
}

#[test]
fn every_shader_has_a_rust_twin_file() {
    let mut shaders: Vec<String> = std::fs::read_dir(root().join("shaders"))
        .expect("shaders/")
        .map(|e| e.expect("a shader").file_name().to_string_lossy().into_owned())
        .filter(|name| name.ends_with(".wgsl"))
        .collect();
    shaders.sort();
    let mut listed: Vec<String> = TWINS.iter().map(|(s, _)| s.to_string()).collect();
    listed.sort();
    assert_eq!(shaders, listed, "every shaders/*.wgsl needs its Rust twin in TWINS");
    for (_, twins) in TWINS {
        for twin in *twins {
            assert!(!rust_files(twin).is_empty(), "{twin} holds no Rust file");
        }
    }
}

#[test]
fn every_wgsl_function_has_a_rust_twin_of_the_same_name() {
    let functions = wgsl_functions();
    let mut missing = Vec::new();
    let mut stale = Vec::new();
    for (shader, twins) in TWINS {
        let mut names = BTreeSet::new();
        for twin in *twins {
            for file in rust_files(twin) {
                names.extend(rust_names(&read(&file)));
            }
        }
        for (_, name) in functions.iter().filter(|(s, _)| s == shader) {
            let exception = EXCEPTIONS.iter().find(|(s, f, _, _)| s == shader && f == name);
            match (names.contains(name), exception) {
                (true, Some(_)) => stale.push(format!("{shader}: `{name}` has a twin in {twins:?} now")),
                (true, None) => {}
                (false, Some((_, _, Some(elsewhere), _))) => {
                    if !rust_names(&read(&root().join(elsewhere))).contains(name) {
                        missing.push(format!("{shader}: `{name}` (its exception names {elsewhere})"));
                    }
                }
                (false, Some((_, _, None, _))) => {}
                (false, None) => missing.push(format!("{shader}: `{name}` (looked in {twins:?})")),
            }
        }
    }
    for (shader, name, _, why) in EXCEPTIONS {
        assert!(!why.is_empty(), "the exception for {shader}: `{name}` needs a reason");
        if !functions.iter().any(|(s, n)| s == shader && n == name) {
            stale.push(format!("{shader}: `{name}` is no longer a WGSL function"));
        }
    }
    assert!(missing.is_empty(), "WGSL functions without a Rust twin of the same name:\n{}", missing.join("\n"));
    assert!(stale.is_empty(), "exceptions no longer needed:\n{}", stale.join("\n"));
}

/// The names this test reads from Rust, on a sample of the forms it meets.
#[test]
fn twin_names_come_from_functions_methods_and_closures() {
    let source = "impl<'a> Path<'a> {\n    pub(crate) fn draw_noise(&mut self) {\n        let ar1 = |s: f64| s;\n    }\n}\n\
                  impl Trig {\n    fn at(theta: f64) -> Trig {}\n}\nfn free() {}\n";
    let names: Vec<String> = rust_names(source).into_iter().collect();
    assert_eq!(names, ["ar1", "at", "draw_noise", "free", "path_draw_noise", "trig_at"]);
}

#[test]
fn the_backends_never_import_from_each_other() {
    for (folder, other) in [("src/engine/gpu", "cpu"), ("src/engine/cpu", "gpu")] {
        let mut files = rust_files(folder);
        for sub in std::fs::read_dir(root().join(folder)).expect("the backend's folder") {
            let sub = sub.expect("an entry").path();
            if sub.is_dir() {
                files.extend(rust_files(sub.strip_prefix(root()).expect("inside the crate").to_str().unwrap()));
            }
        }
        // `cpu::` or `gpu::` as a path segment (not `wgpu::`), outside comments.
        let needle = format!("{other}::");
        let names_other = |line: &str| {
            let code = line.split("//").next().unwrap_or("");
            code.match_indices(&needle)
                .any(|(at, _)| !code[..at].ends_with(|c: char| c.is_ascii_alphanumeric() || c == '_'))
        };
        for file in files {
            let text = read(&file);
            let hit = text.lines().find(|l| names_other(l));
            assert!(hit.is_none(), "{} reaches into the {other} backend: {}", file.display(), hit.unwrap_or(""));
        }
    }
}
