//! Trajectories and thermo rows streamed to disk.
//!
//! Snapshots are written in LAMMPS's text dump format with the columns
//! `id mol type x y z ix iy iz vx vy vz` (then `fx fy fz` if asked), so
//! OVITO and LAMMPS's `read_dump` read them, and grains that cross periodic
//! faces can be rebuilt whole from the image flags. Both engines write
//! through [`DumpWriter`], so their files have the same form. Thermo rows
//! go to a plain text file as they are recorded, so a run of millions of
//! steps does not grow in memory.

use crate::engine::SimBox;
use std::fmt::Write as _;
use std::io::{BufRead, BufWriter, Write};
use std::path::{Path, PathBuf};

/// Why a trajectory or thermo file could not be written or read.
pub use crate::file_error::TextFileError as TrajectoryError;

/// One state of the particles, in atom id order.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Global step.
    pub step: u64,
    /// Atom id per particle (the scene's `particles.ids`), increasing;
    /// `None` for `1..=N` (particle `i` is atom `i + 1`).
    pub id: Option<Vec<u64>>,
    /// The box.
    pub simbox: SimBox,
    /// Grain id per particle (molecule id minus 1).
    pub grain: Vec<u32>,
    /// Type per particle, from 1.
    pub kind: Vec<u32>,
    /// Positions (d), in or near the box.
    pub x: Vec<[f64; 3]>,
    /// Periodic image flags.
    pub image: Vec<[i32; 3]>,
    /// Velocities (d / tau).
    pub v: Vec<[f64; 3]>,
    /// Forces (k d), if recorded.
    pub f: Option<Vec<[f64; 3]>>,
}

impl Frame {
    /// Unwrapped positions, `x + image . box vectors`.
    pub fn unwrapped(&self) -> Vec<[f64; 3]> {
        self.x
            .iter()
            .zip(&self.image)
            .map(|(x, n)| {
                let s = self.simbox.image_vector(n);
                [x[0] + s[0], x[1] + s[1], x[2] + s[2]]
            })
            .collect()
    }
}

/// Opens `path` for appending after its first `length` bytes, dropping
/// the rest (written after a checkpoint, by a run that then died). A file
/// shorter than `length` is not the one the checkpoint knew.
fn reopen_at(path: &Path, length: u64) -> Result<std::fs::File, TrajectoryError> {
    use std::io::{Seek, SeekFrom};
    let mut file = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(path)
        .map_err(io_error(path))?;
    let found = file.metadata().map_err(io_error(path))?.len();
    if found < length {
        return Err(TrajectoryError::Io {
            path: path.to_path_buf(),
            cause: std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                format!(
                    "it has {found} bytes, fewer than the {length} it had at the checkpoint (was it replaced?)"
                ),
            ),
        });
    }
    file.set_len(length).map_err(io_error(path))?;
    file.seek(SeekFrom::End(0)).map_err(io_error(path))?;
    Ok(file)
}

/// Flushes `out` and returns the length of its file.
fn written_length(out: &mut BufWriter<std::fs::File>, path: &Path) -> Result<u64, TrajectoryError> {
    out.flush().map_err(io_error(path))?;
    out.get_ref()
        .metadata()
        .map(|m| m.len())
        .map_err(io_error(path))
}

/// Writes frames to a LAMMPS text dump.
#[derive(Debug)]
pub struct DumpWriter {
    path: PathBuf,
    out: BufWriter<std::fs::File>,
    last_step: Option<u64>,
}

fn io_error(path: &Path) -> impl FnOnce(std::io::Error) -> TrajectoryError + '_ {
    move |cause| TrajectoryError::Io {
        path: path.to_path_buf(),
        cause,
    }
}

impl DumpWriter {
    /// Creates (truncates) the dump file.
    pub fn create(path: &Path) -> Result<Self, TrajectoryError> {
        let file = std::fs::File::create(path).map_err(io_error(path))?;
        Ok(Self {
            path: path.to_path_buf(),
            out: BufWriter::new(file),
            last_step: None,
        })
    }

    /// The file written to.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Reopens a dump this writer wrote, cut back to its first `length`
    /// bytes (its length at a checkpoint), to append from there; the frame
    /// of `last_step` is the last one in it.
    pub fn reopen(
        path: &Path,
        length: u64,
        last_step: Option<u64>,
    ) -> Result<Self, TrajectoryError> {
        Ok(Self {
            path: path.to_path_buf(),
            out: BufWriter::new(reopen_at(path, length)?),
            last_step,
        })
    }

    /// The bytes written so far, all flushed to the file.
    pub fn length(&mut self) -> Result<u64, TrajectoryError> {
        written_length(&mut self.out, &self.path)
    }

    /// The step of the last frame written.
    pub fn last_step(&self) -> Option<u64> {
        self.last_step
    }

    /// Appends `frame`, unless a frame of the same step was the last one
    /// written (a stage's first state is the previous stage's last).
    pub fn write(&mut self, frame: &Frame) -> Result<(), TrajectoryError> {
        if self.last_step == Some(frame.step) {
            return Ok(());
        }
        let text = dump_text(frame);
        self.out
            .write_all(text.as_bytes())
            .and_then(|_| self.out.flush())
            .map_err(io_error(&self.path))?;
        self.last_step = Some(frame.step);
        Ok(())
    }
}

fn num(v: f64) -> String {
    // Shortest representation that reads back to the same f64.
    format!("{v:?}")
}

/// The dump text of one frame.
pub fn dump_text(frame: &Frame) -> String {
    let b = &frame.simbox;
    let n = frame.x.len();
    let mut s = String::with_capacity(64 + n * 160);
    let _ = write!(
        s,
        "ITEM: TIMESTEP\n{}\nITEM: NUMBER OF ATOMS\n{n}\n",
        frame.step
    );
    let pbc: Vec<&str> = b
        .periodic
        .iter()
        .map(|&p| if p { "pp" } else { "ff" })
        .collect();
    let hi = |d: usize| b.lo[d] + b.lengths[d];
    if b.tilt.iter().any(|&t| t != 0.0) {
        // LAMMPS writes the bounding box of the tilted cell, then the tilt.
        let [xy, xz, yz] = b.tilt;
        let xlo = b.lo[0] + [0.0, xy, xz, xy + xz].into_iter().fold(0.0, f64::min);
        let xhi = hi(0) + [0.0, xy, xz, xy + xz].into_iter().fold(0.0, f64::max);
        let ylo = b.lo[1] + yz.min(0.0);
        let yhi = hi(1) + yz.max(0.0);
        let _ = writeln!(s, "ITEM: BOX BOUNDS xy xz yz {}", pbc.join(" "));
        let _ = writeln!(s, "{} {} {}", num(xlo), num(xhi), num(xy));
        let _ = writeln!(s, "{} {} {}", num(ylo), num(yhi), num(xz));
        let _ = writeln!(s, "{} {} {}", num(b.lo[2]), num(hi(2)), num(yz));
    } else {
        let _ = writeln!(s, "ITEM: BOX BOUNDS {}", pbc.join(" "));
        for d in 0..3 {
            let _ = writeln!(s, "{} {}", num(b.lo[d]), num(hi(d)));
        }
    }
    s.push_str("ITEM: ATOMS id mol type x y z ix iy iz vx vy vz");
    s.push_str(if frame.f.is_some() {
        " fx fy fz\n"
    } else {
        "\n"
    });
    for i in 0..n {
        let (x, m, v) = (&frame.x[i], &frame.image[i], &frame.v[i]);
        let _ = write!(
            s,
            "{} {} {} {} {} {} {} {} {} {} {} {}",
            frame.id.as_ref().map_or(i as u64 + 1, |id| id[i]),
            frame.grain[i] + 1,
            frame.kind[i],
            num(x[0]),
            num(x[1]),
            num(x[2]),
            m[0],
            m[1],
            m[2],
            num(v[0]),
            num(v[1]),
            num(v[2])
        );
        if let Some(f) = &frame.f {
            let _ = write!(s, " {} {} {}", num(f[i][0]), num(f[i][1]), num(f[i][2]));
        }
        s.push('\n');
    }
    s
}

/// One atom line of a dump: id, grain, type, x, image, v, f.
type DumpAtom = (u64, u32, u32, [f64; 3], [i32; 3], [f64; 3], [f64; 3]);

/// Reads every frame of a LAMMPS text dump with at least the columns
/// `id x y z` (any order; `mol`, `type`, `ix iy iz`, `vx vy vz`, `fx fy
/// fz` when present). Atoms are ordered by id; ids need not be 1..N
/// (they are kept in [`Frame::id`]), but are positive.
pub fn read_dump(path: &Path) -> Result<Vec<Frame>, TrajectoryError> {
    let file = std::fs::File::open(path).map_err(io_error(path))?;
    let mut lines = std::io::BufReader::new(file).lines().enumerate();
    let bad = |line: usize, reason: String| TrajectoryError::Malformed {
        path: path.to_path_buf(),
        line: line + 1,
        reason,
    };
    let mut next = |what: &str| -> Result<(usize, String), TrajectoryError> {
        match lines.next() {
            Some((k, Ok(l))) => Ok((k, l)),
            Some((_, Err(e))) => Err(io_error(path)(e)),
            None => Err(bad(usize::MAX - 1, format!("file ends before {what}"))),
        }
    };
    let mut frames = Vec::new();
    loop {
        let header = match next("a frame") {
            Ok((_, l)) if l.trim().is_empty() => continue,
            Ok((k, l)) => (k, l),
            Err(TrajectoryError::Malformed { .. }) => break,
            Err(e) => return Err(e),
        };
        if header.1.trim() != "ITEM: TIMESTEP" {
            return Err(bad(
                header.0,
                format!("expected `ITEM: TIMESTEP`, found `{}`", header.1),
            ));
        }
        let (k, l) = next("the timestep")?;
        let step: u64 = l
            .trim()
            .parse()
            .map_err(|_| bad(k, format!("bad timestep `{l}`")))?;
        let (k, l) = next("the atom count")?;
        if l.trim() != "ITEM: NUMBER OF ATOMS" {
            return Err(bad(
                k,
                format!("expected `ITEM: NUMBER OF ATOMS`, found `{l}`"),
            ));
        }
        let (k, l) = next("the atom count")?;
        let n: usize = l
            .trim()
            .parse()
            .map_err(|_| bad(k, format!("bad atom count `{l}`")))?;
        let (k, l) = next("the box")?;
        let Some(rest) = l.trim().strip_prefix("ITEM: BOX BOUNDS") else {
            return Err(bad(k, format!("expected `ITEM: BOX BOUNDS`, found `{l}`")));
        };
        let words: Vec<&str> = rest.split_whitespace().collect();
        let triclinic = words.first() == Some(&"xy");
        let flags = if triclinic {
            &words[3.min(words.len())..]
        } else {
            &words[..]
        };
        let periodic = [0, 1, 2].map(|d| flags.get(d).is_none_or(|f| *f == "pp"));
        let mut rows = [[0.0f64; 3]; 3];
        for row in &mut rows {
            let (k, l) = next("the box bounds")?;
            let v: Result<Vec<f64>, _> = l.split_whitespace().map(str::parse).collect();
            let v = v.map_err(|_| bad(k, format!("bad box bounds `{l}`")))?;
            if v.len() < if triclinic { 3 } else { 2 } {
                return Err(bad(k, format!("too few box bounds in `{l}`")));
            }
            row[..v.len().min(3)].copy_from_slice(&v[..v.len().min(3)]);
        }
        let (tilt, lo, hi) = if triclinic {
            let [xy, xz, yz] = [rows[0][2], rows[1][2], rows[2][2]];
            let xlo = rows[0][0] - [0.0, xy, xz, xy + xz].into_iter().fold(0.0, f64::min);
            let xhi = rows[0][1] - [0.0, xy, xz, xy + xz].into_iter().fold(0.0, f64::max);
            let ylo = rows[1][0] - yz.min(0.0);
            let yhi = rows[1][1] - yz.max(0.0);
            ([xy, xz, yz], [xlo, ylo, rows[2][0]], [xhi, yhi, rows[2][1]])
        } else {
            (
                [0.0; 3],
                [rows[0][0], rows[1][0], rows[2][0]],
                [rows[0][1], rows[1][1], rows[2][1]],
            )
        };
        let simbox = SimBox {
            lo,
            lengths: [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]],
            tilt,
            periodic,
        };
        let (k, l) = next("the atom columns")?;
        let Some(cols) = l.trim().strip_prefix("ITEM: ATOMS") else {
            return Err(bad(k, format!("expected `ITEM: ATOMS`, found `{l}`")));
        };
        let cols: Vec<&str> = cols.split_whitespace().collect();
        let at = |name: &str| cols.iter().position(|c| *c == name);
        let (Some(id), Some(cx), Some(cy), Some(cz)) = (at("id"), at("x"), at("y"), at("z")) else {
            return Err(bad(k, "the atom columns need at least `id x y z`".into()));
        };
        let image_cols = (at("ix"), at("iy"), at("iz"));
        let vel_cols = (at("vx"), at("vy"), at("vz"));
        let force_cols = (at("fx"), at("fy"), at("fz"));
        let mut atoms: Vec<DumpAtom> = Vec::with_capacity(n);
        for _ in 0..n {
            let (k, l) = next("all atoms")?;
            let w: Vec<&str> = l.split_whitespace().collect();
            if w.len() < cols.len() {
                return Err(bad(
                    k,
                    format!("{} values for {} columns", w.len(), cols.len()),
                ));
            }
            let f = |c: usize| -> Result<f64, TrajectoryError> {
                w[c].parse::<f64>()
                    .map_err(|_| bad(k, format!("`{}` is not a number", w[c])))
            };
            let int = |c: usize| -> Result<i64, TrajectoryError> {
                w[c].parse::<i64>()
                    .map_err(|_| bad(k, format!("`{}` is not an integer", w[c])))
            };
            let triple = |c: (Option<usize>, Option<usize>, Option<usize>)| -> Result<[f64; 3], TrajectoryError> {
                match c {
                    (Some(a), Some(b), Some(c)) => Ok([f(a)?, f(b)?, f(c)?]),
                    _ => Ok([0.0; 3]),
                }
            };
            let image = match image_cols {
                (Some(a), Some(b), Some(c)) => [int(a)? as i32, int(b)? as i32, int(c)? as i32],
                _ => [0; 3],
            };
            let mol = at("mol").map(&int).transpose()?.unwrap_or(1);
            let kind = at("type").map(&int).transpose()?.unwrap_or(1);
            if mol < 1 || kind < 1 {
                return Err(bad(k, "molecule ids and types count from 1".into()));
            }
            let atom_id = int(id)?;
            if atom_id < 1 {
                return Err(bad(k, format!("atom id {atom_id}: ids count from 1")));
            }
            atoms.push((
                atom_id as u64,
                (mol - 1) as u32,
                kind as u32,
                [f(cx)?, f(cy)?, f(cz)?],
                image,
                triple(vel_cols)?,
                triple(force_cols)?,
            ));
        }
        atoms.sort_by_key(|a| a.0);
        if let Some(w) = atoms.windows(2).find(|w| w[0].0 == w[1].0) {
            return Err(bad(
                k,
                format!(
                    "atom id {} appears twice in the frame of step {step}",
                    w[0].0
                ),
            ));
        }
        let ids: Vec<u64> = atoms.iter().map(|a| a.0).collect();
        let id = Some(ids).filter(|ids| !crate::scene::model::is_default_numbering(ids));
        frames.push(Frame {
            step,
            id,
            simbox,
            grain: atoms.iter().map(|a| a.1).collect(),
            kind: atoms.iter().map(|a| a.2).collect(),
            x: atoms.iter().map(|a| a.3).collect(),
            image: atoms.iter().map(|a| a.4).collect(),
            v: atoms.iter().map(|a| a.5).collect(),
            f: force_cols.0.map(|_| atoms.iter().map(|a| a.6).collect()),
        });
    }
    Ok(frames)
}

/// Streams thermo rows to a text file: per stage a `# stage` line and a
/// `#` line of column names, then one row per recorded step, values
/// separated by spaces, each written in full precision.
#[derive(Debug)]
pub struct ThermoWriter {
    path: PathBuf,
    out: BufWriter<std::fs::File>,
}

impl ThermoWriter {
    /// Creates (truncates) the thermo file.
    pub fn create(path: &Path) -> Result<Self, TrajectoryError> {
        let file = std::fs::File::create(path).map_err(io_error(path))?;
        Ok(Self {
            path: path.to_path_buf(),
            out: BufWriter::new(file),
        })
    }

    /// Reopens a thermo file this writer wrote, cut back to its first
    /// `length` bytes (its length at a checkpoint), to append from there.
    pub fn reopen(path: &Path, length: u64) -> Result<Self, TrajectoryError> {
        Ok(Self {
            path: path.to_path_buf(),
            out: BufWriter::new(reopen_at(path, length)?),
        })
    }

    /// The bytes written so far, all flushed to the file.
    pub fn length(&mut self) -> Result<u64, TrajectoryError> {
        written_length(&mut self.out, &self.path)
    }

    /// The file written to.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Starts a stage's block.
    pub fn begin_stage(
        &mut self,
        index: usize,
        name: &str,
        columns: &[String],
    ) -> Result<(), TrajectoryError> {
        let text = format!("# stage {index} {name}\n# {}\n", columns.join(" "));
        self.out
            .write_all(text.as_bytes())
            .map_err(io_error(&self.path))
    }

    /// Appends one row.
    pub fn row(&mut self, row: &[f64]) -> Result<(), TrajectoryError> {
        let text: Vec<String> = row.iter().map(|&v| num(v)).collect();
        writeln!(self.out, "{}", text.join(" ")).map_err(io_error(&self.path))
    }

    /// Flushes what was written (at the end of each stage, so a failed
    /// run keeps every finished stage on disk).
    pub fn flush(&mut self) -> Result<(), TrajectoryError> {
        self.out.flush().map_err(io_error(&self.path))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(tilt: [f64; 3], forces: bool) -> Frame {
        Frame {
            step: 42,
            id: Some(vec![3, 8, 20]),
            simbox: SimBox {
                lo: [-1.0, 0.5, 2.0],
                lengths: [10.0, 8.0, 6.0],
                tilt,
                periodic: [true, true, false],
            },
            grain: vec![0, 3, 3],
            kind: vec![1, 2, 1],
            x: vec![
                [0.1, 0.2, 0.3],
                [1.0 / 3.0, -0.0, 5.9999999999],
                [9.0, 7.5, 2.5],
            ],
            image: vec![[0, 0, 0], [-1, 2, 0], [1, 0, 0]],
            v: vec![[1e-300, 0.0, -1.5], [0.25, 1e10, 3.0], [0.0; 3]],
            f: forces.then(|| vec![[1.0, 2.0, 3.0], [-0.1, 0.2, 0.3], [0.0; 3]]),
        }
    }

    #[test]
    fn dump_round_trips_bit_for_bit_orthogonal_and_tilted() {
        for (tilt, forces) in [([0.0; 3], false), ([1.5, -0.5, 0.75], true)] {
            let f = frame(tilt, forces);
            let dir = std::env::temp_dir().join(format!("bpm-dump-test-{}", std::process::id()));
            std::fs::create_dir_all(&dir).unwrap();
            let path = dir.join(format!("t{forces}.dump"));
            let mut w = DumpWriter::create(&path).unwrap();
            w.write(&f).unwrap();
            w.write(&f).unwrap(); // same step: written once
            let mut g = f.clone();
            g.step = 43;
            w.write(&g).unwrap();
            drop(w);
            let back = read_dump(&path).unwrap();
            assert_eq!(back.len(), 2);
            assert_eq!(back[1].step, 43);
            // Box bounds go through min/max sums, so the box is compared to
            // round-off; everything else bit for bit.
            let b = &back[0].simbox;
            for d in 0..3 {
                assert!((b.lo[d] - f.simbox.lo[d]).abs() < 1e-12);
                assert!((b.lengths[d] - f.simbox.lengths[d]).abs() < 1e-12);
                assert_eq!(b.tilt[d], f.simbox.tilt[d]);
            }
            assert_eq!(b.periodic, f.simbox.periodic);
            let mut a = back[0].clone();
            a.simbox = f.simbox.clone();
            assert_eq!(a, f);
        }
    }

    #[test]
    fn reader_sorts_atoms_by_id_and_names_the_bad_line() {
        let dir = std::env::temp_dir().join(format!("bpm-dump-read-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("user.dump");
        std::fs::write(
            &path,
            "ITEM: TIMESTEP\n7\nITEM: NUMBER OF ATOMS\n2\nITEM: BOX BOUNDS pp pp pp\n0 5\n0 5\n0 5\nITEM: ATOMS x y z id\n1 1 1 20\n2 2 2 9\n",
        )
        .unwrap();
        let frames = read_dump(&path).unwrap();
        assert_eq!(frames[0].x, vec![[2.0; 3], [1.0; 3]]);
        assert_eq!(frames[0].id, Some(vec![9, 20]));
        std::fs::write(
            &path,
            "ITEM: TIMESTEP\n7\nITEM: NUMBER OF ATOMS\n2\nITEM: BOX BOUNDS pp pp pp\n0 5\n0 5\n0 5\nITEM: ATOMS id x y z\n1 1 1 1\n2 2 x 2\n",
        )
        .unwrap();
        let err = read_dump(&path).unwrap_err().to_string();
        assert!(err.contains("line 11") && err.contains("`x`"), "{err}");
    }
}
