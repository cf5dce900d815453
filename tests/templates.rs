//! The input templates compiled into the binary (`bpm::lammps::templates`)
//! are exactly the files of `lammps_inputs/`: a file added there without an
//! entry in the table fails here.

mod common;

use bpm::lammps::templates::{template, write_templates, TEMPLATES};
use std::collections::BTreeSet;
use std::path::Path;

/// Every file under `dir`, as `/`-separated paths relative to `root`.
fn files_under(root: &Path, dir: &Path, out: &mut BTreeSet<String>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            files_under(root, &path, out);
        } else {
            let rel = path.strip_prefix(root).unwrap();
            let parts: Vec<_> = rel.iter().map(|p| p.to_string_lossy()).collect();
            out.insert(parts.join("/"));
        }
    }
}

#[test]
fn every_file_of_lammps_inputs_is_embedded() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("lammps_inputs");
    let mut on_disk = BTreeSet::new();
    files_under(&root, &root, &mut on_disk);
    let table: BTreeSet<String> = TEMPLATES.iter().map(|(n, _)| n.to_string()).collect();
    assert_eq!(TEMPLATES.len(), table.len(), "a template is listed twice");
    let missing: Vec<_> = on_disk.difference(&table).collect();
    let stale: Vec<_> = table.difference(&on_disk).collect();
    assert!(
        missing.is_empty(),
        "files in lammps_inputs/ missing from TEMPLATES in src/lammps/templates.rs: {missing:?}"
    );
    assert!(
        stale.is_empty(),
        "TEMPLATES lists files no longer in lammps_inputs/: {stale:?}"
    );
    for name in &on_disk {
        let text = std::fs::read_to_string(root.join(name)).unwrap();
        assert_eq!(
            template(name),
            Some(text.as_str()),
            "{name} differs from the embedded copy"
        );
    }
}

#[test]
fn templates_are_written_into_the_work_folder() {
    let dir = common::scratch_dir("templates");
    for _ in 0..2 {
        // The second pass finds identical files and leaves them.
        let inputs = write_templates(&dir).unwrap();
        assert!(inputs.is_absolute());
        assert_eq!(inputs, std::path::absolute(dir.join("inputs")).unwrap());
        for (name, text) in TEMPLATES {
            assert_eq!(&std::fs::read_to_string(inputs.join(name)).unwrap(), text);
        }
    }
    // Every `include ${inputs}/X` of a template names an embedded template.
    for (name, text) in TEMPLATES {
        for line in text.lines() {
            if let Some(rest) = line.trim_start().strip_prefix("include") {
                if let Some(target) = rest.trim().strip_prefix("${inputs}/") {
                    assert!(
                        template(target).is_some(),
                        "{name} includes unknown {target}"
                    );
                }
            }
        }
    }
    // A changed file is replaced; no temporary files are left behind.
    let setup = dir.join("inputs/setup.in");
    std::fs::write(&setup, "edited").unwrap();
    write_templates(&dir).unwrap();
    assert_eq!(
        std::fs::read_to_string(&setup).unwrap(),
        template("setup.in").unwrap()
    );
    let mut written = BTreeSet::new();
    files_under(&dir.join("inputs"), &dir.join("inputs"), &mut written);
    assert_eq!(written.len(), TEMPLATES.len(), "{written:?}");
    let _ = std::fs::remove_dir_all(&dir);
}
