//! The runtime's modules form layers (ARCHITECTURE.md, "The runtime's
//! layers"): every `crate::` path in the code of `runtime/src` (unit tests
//! and comments aside) names a module of its own layer or of a layer below,
//! and the modules' import graph has no cycle.
//!
//! The layers, bottom up, are [`LAYERS`]; a module not listed fails the
//! test, so a new module must be given its place.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The runtime's modules by layer, bottom up. A module is named by its path
/// below the crate root; a file belongs to the longest listed prefix of its
/// own module path.
const LAYERS: &[(&str, &[&str])] = &[
    ("ground", &["math", "domain", "material", "validate"]),
    (
        "spectrum data",
        &["spectrum::colour", "spectrum::optical", "materials"],
    ),
    (
        "table files",
        &["tables::format", "tables::interp", "tables::mmap"],
    ),
    (
        "table readers",
        &[
            "tables::smith_g1",
            "tables::sigma_ratio",
            "tables::convolution",
            "tables::diffuse_fresnel",
            "tables::albedo",
            "tables::sh_brdf",
        ],
    ),
    (
        "distributions",
        &["model::epd", "model::kcorr", "model::fresnel"],
    ),
    (
        "bakes and samplers",
        &["bake", "bake::visible", "bake::halo"],
    ),
    ("BRDFs", &["brdf"]),
    (
        "front doors",
        &["io::merl", "io::desc", "bxdf", "table_set"],
    ),
];

/// Folders and files that hold no code of a layer: the crate root (it
/// declares and re-exports), the folders' `mod.rs` that only declare, and
/// the test helper.
const UNLAYERED: &[&str] = &["", "tables", "model", "spectrum", "io", "test_rng"];

fn layer_of(module: &str) -> Option<(usize, &'static str)> {
    let mut best: Option<(usize, &'static str)> = None;
    for (k, (_, modules)) in LAYERS.iter().enumerate() {
        for &m in *modules {
            let matches = module == m || module.starts_with(&format!("{m}::"));
            if matches && best.is_none_or(|(_, b)| m.len() > b.len()) {
                best = Some((k, m));
            }
        }
    }
    best
}

/// Every `.rs` file under `dir` with its module path (`tables/format/mod.rs`
/// → `tables::format`); unit-test files (`tests.rs`) are left out.
fn sources(dir: &Path, prefix: &str, out: &mut Vec<(String, PathBuf)>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for path in entries {
        let name = path.file_name().unwrap().to_str().unwrap().to_owned();
        let join = |n: &str| {
            if prefix.is_empty() {
                n.to_owned()
            } else {
                format!("{prefix}::{n}")
            }
        };
        if path.is_dir() {
            sources(&path, &join(&name), out);
        } else if let Some(stem) = name.strip_suffix(".rs") {
            if stem == "tests" || stem.ends_with("_data") {
                continue; // unit tests; `include!`d data rows
            }
            let module = match stem {
                "mod" => prefix.to_owned(),
                "lib" => String::new(),
                _ => join(stem),
            };
            out.push((module, path));
        }
    }
}

/// The code of a file without its comments and its trailing unit-test
/// module: lines up to the first `#[cfg(...test...)]` that opens `mod tests`.
fn code(text: &str) -> String {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = String::new();
    for (k, line) in lines.iter().enumerate() {
        let t = line.trim_start();
        if t.starts_with("#[cfg(")
            && t.contains("test")
            && lines.get(k + 1).is_some_and(|n| n.starts_with("mod tests"))
        {
            break;
        }
        if t.starts_with("//") {
            continue;
        }
        out.push_str(&without_strings(line.split(" // ").next().unwrap_or("")));
        out.push('\n');
    }
    out
}

/// `line` with the contents of its string literals removed.
fn without_strings(line: &str) -> String {
    let (mut out, mut inside, mut escaped) = (String::new(), false, false);
    for c in line.chars() {
        if inside {
            match (escaped, c) {
                (false, '\\') => escaped = true,
                (false, '"') => inside = false,
                _ => escaped = false,
            }
            continue;
        }
        if c == '"' {
            inside = true;
        }
        out.push(c);
    }
    out
}

/// The modules `code` names through `crate::a::b…` paths (longest listed prefix).
fn imports(code: &str) -> BTreeSet<String> {
    let mut found = BTreeSet::new();
    let mut rest = code;
    while let Some(at) = rest.find("crate::") {
        let before = rest[..at].chars().next_back();
        rest = &rest[at + "crate::".len()..];
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == '$') {
            continue; // `$crate::`, `twoscale_crate::`
        }
        let path: String = rest
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_' || *c == ':')
            .collect();
        let segments: Vec<&str> = path
            .split("::")
            .take_while(|s| s.chars().next().is_some_and(|c| c.is_lowercase()))
            .collect();
        if !segments.is_empty() {
            found.insert(segments.join("::"));
        }
    }
    found
}

#[test]
fn the_runtime_is_layered_without_cycles() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("runtime/src");
    let mut files = Vec::new();
    sources(&root, "", &mut files);
    // unit → units it imports
    let mut graph: BTreeMap<&'static str, BTreeSet<&'static str>> = BTreeMap::new();
    let mut upward = Vec::new();
    let mut edges = 0;
    for (module, path) in &files {
        if UNLAYERED.contains(&module.as_str()) {
            continue;
        }
        let (layer, unit) = layer_of(module)
            .unwrap_or_else(|| panic!("runtime module `{module}` has no layer in LAYERS"));
        let text = std::fs::read_to_string(path).unwrap();
        for import in imports(&code(&text)) {
            if UNLAYERED.contains(&import.as_str()) {
                continue; // a re-export of the crate root or a folder
            }
            let Some((to_layer, to_unit)) = layer_of(&import) else {
                // `crate::Name` re-exports and macros are not modules
                continue;
            };
            if to_unit == unit {
                continue;
            }
            edges += 1;
            graph.entry(unit).or_default().insert(to_unit);
            if to_layer > layer {
                upward.push(format!(
                    "{} ({}) imports {} ({})",
                    module, LAYERS[layer].0, import, LAYERS[to_layer].0
                ));
            }
        }
    }
    assert!(
        edges > 50,
        "only {edges} imports found: is the parser broken?"
    );
    assert!(
        upward.is_empty(),
        "imports running up the layers:\n{}",
        upward.join("\n")
    );
    // No cycle: depth-first search with colours.
    fn visit<'a>(
        u: &'a str,
        graph: &BTreeMap<&'a str, BTreeSet<&'a str>>,
        state: &mut BTreeMap<&'a str, u8>,
        stack: &mut Vec<&'a str>,
    ) {
        match state.get(u) {
            Some(2) => return,
            Some(1) => panic!("import cycle: {} -> {u}", stack.join(" -> ")),
            _ => {}
        }
        state.insert(u, 1);
        stack.push(u);
        for &v in graph.get(u).into_iter().flatten() {
            visit(v, graph, state, stack);
        }
        stack.pop();
        state.insert(u, 2);
    }
    let mut state = BTreeMap::new();
    for &u in graph.keys() {
        visit(u, &graph, &mut state, &mut Vec::new());
    }
}

/// The parser sees what the test relies on: paths, groups, and not comments.
#[test]
fn imports_are_read_from_code_only() {
    let text = "use crate::tables::format::{Table, TableId};\n\
                // use crate::brdf::TwoScale;\n\
                /// [`crate::io::desc`]\n\
                let x = crate::math::sqrt(2.0); // crate::bxdf\n\
                let s = \"crate::brdf\";\n\
                $crate::AlignedBytes\n\
                #[cfg(test)]\nmod tests {\n use crate::table_set::TableSet;\n}\n";
    let found = imports(&code(text));
    let expected: BTreeSet<String> = ["tables::format", "math::sqrt"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    assert_eq!(found, expected);
}
