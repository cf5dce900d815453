//! `docs/architecture.md` stays true: every path its "Where to add" table
//! names exists, and the layers it draws have no cycle.

use std::path::Path;

#[test]
fn every_path_in_the_where_to_add_table_exists() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let doc = std::fs::read_to_string(root.join("docs/architecture.md")).unwrap();
    let table: Vec<&str> = doc
        .split("## Where to add")
        .nth(1)
        .expect("a Where to add section")
        .lines()
        .take_while(|l| !l.starts_with("## "))
        .filter(|l| l.starts_with("| ") && !l.starts_with("| ---") && !l.starts_with("| to add"))
        .collect();
    assert_eq!(table.len(), 6, "rows: {table:?}");
    let mut checked = 0;
    for row in table {
        // Code spans are every other piece between backticks.
        for span in row.split('`').skip(1).step_by(2) {
            let first = span.split_whitespace().next().unwrap_or("");
            let roots = ["src/", "tests/", "lammps-plugin/", "lammps_inputs/"];
            if !roots.iter().any(|r| first.starts_with(r)) || first.contains('<') {
                continue;
            }
            assert!(
                root.join(first).exists(),
                "{first} (named in docs/architecture.md)"
            );
            checked += 1;
        }
    }
    assert!(checked >= 25, "only {checked} paths found in the table");
}

/// The layers point one way: no file of `src/` depends on itself through
/// others, and no folder does (`scripts/import-graph.py`, test modules
/// aside).
#[test]
fn no_file_or_folder_of_the_crate_depends_on_itself() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = std::process::Command::new("python3")
        .arg(root.join("scripts/import-graph.py"))
        .output()
        .expect("python3 runs scripts/import-graph.py");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    assert!(
        text.contains("file cycles: 0") && text.contains("folder cycles: 0"),
        "{text}"
    );
}
