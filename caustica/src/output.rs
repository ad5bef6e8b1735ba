//! Writing frames: linear EXR for data, tone-mapped sRGB PNG for looking, JSON stats.

use caustica_core::frame::image::{tone_map, Image};
use std::path::{Path, PathBuf};

/// Reads the first RGBA layer of an OpenEXR file as a linear f32 image (what
/// [`write_exr`] writes).
pub fn read_exr(path: &Path) -> Result<Image, String> {
    use exr::prelude::*;
    let img = read_first_rgba_layer_from_file(
        path,
        |res, _| {
            let (w, h) = (res.width(), res.height());
            (w, vec![[0.0f32; 4]; w * h])
        },
        |(w, px), pos, (r, g, b, a): (f32, f32, f32, f32)| {
            px[pos.y() * *w + pos.x()] = [r, g, b, a];
        },
    )
    .map_err(|e| format!("{}: {e}", path.display()))?;
    let size = img.layer_data.size;
    let (_, pixels) = img.layer_data.channel_data.pixels;
    Ok(caustica_core::frame::image::Image::new(
        size.width() as u32,
        size.height() as u32,
        pixels,
    ))
}

/// Writes a linear RGBA f32 OpenEXR file: RLE-compressed 64x64 tiles stored in increasing
/// order by one thread, so two identical images give byte-identical files (hash-based
/// caches and golden files work).
pub fn write_exr(path: &Path, img: &Image) -> Result<(), String> {
    use exr::prelude::*;
    let w = img.width as usize;
    let channels = SpecificChannels::rgba(|Vec2(x, y): Vec2<usize>| {
        let p = img.pixels[y * w + x];
        (p[0], p[1], p[2], p[3])
    });
    let encoding = Encoding {
        line_order: LineOrder::Increasing,
        ..Encoding::FAST_LOSSLESS
    };
    write_whole(path, |partial| {
        Image::from_encoded_channels((w, img.height as usize), encoding, channels)
            .write()
            .non_parallel()
            .to_file(partial)
            .map_err(|e| format!("{}: {e}", path.display()))
    })
}

/// A file-name stem made from `name` (a scene name from a scene file, say) that cannot
/// leave the output folder: ASCII letters, digits, `-`, `_` and inner `.` are kept, every
/// other character (separators, NUL, `..` at the start, non-ASCII) becomes `_`, the result
/// is at most 64 characters, and an empty result is `scene`.
pub fn file_stem(name: &str) -> String {
    let mut s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' || c == '.' {
                c
            } else {
                '_'
            }
        })
        .collect();
    // no leading dot: no `..`, no hidden file
    while s.starts_with('.') {
        s.replace_range(0..1, "_");
    }
    s.truncate(64);
    if s.is_empty() {
        "scene".into()
    } else {
        s
    }
}

/// Creates the output folder `dir` and checks that a file can be written there, before
/// any work whose results would be written there; the error starts with `--out` and
/// names the path (see [`prepare_folder`]).
pub fn prepare_output_dir(dir: &Path) -> Result<(), String> {
    prepare_folder(dir).map_err(|e| format!("--out {e}"))
}

/// Creates the folder `dir` (and its parents) and checks that a file can be written
/// there. The error starts with the path and says what is wrong: a file where the folder
/// or one of its parents must be, the operating system's error creating it, or that it
/// is not writable (permissions, a read-only file system).
pub fn prepare_folder(dir: &Path) -> Result<(), String> {
    make_folder(dir)?;
    check_writable(dir)
}

/// Creates the folder `dir` (and its parents) where it is not there yet; the errors of
/// [`prepare_folder`] but the last.
pub fn make_folder(dir: &Path) -> Result<(), String> {
    let shown = dir.display();
    // the nearest part of the path that exists must be a folder
    if let Some(existing) = dir
        .ancestors()
        .filter(|a| !a.as_os_str().is_empty())
        .find(|a| a.exists())
    {
        if !existing.is_dir() {
            return Err(if existing == dir {
                format!("{shown}: a file is there, not a folder")
            } else {
                format!("{shown}: {} is a file, not a folder", existing.display())
            });
        }
    }
    std::fs::create_dir_all(dir).map_err(|e| format!("{shown}: cannot create the folder: {e}"))
}

/// Whether a file can be made in the existing folder `dir` (a probe file, written and
/// removed); the error names the folder.
pub fn check_writable(dir: &Path) -> Result<(), String> {
    let probe = dir.join(format!(".caustica-write-test-{}", std::process::id()));
    std::fs::write(&probe, b"").map_err(|e| format!("{}: not writable: {e}", dir.display()))?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

/// The names, sorted, of the files in the folder `dir` that a run did not write: every
/// regular file directly in `dir` whose name is not the file name of one of `written`
/// (the paths the run wrote there). Subfolders, symbolic links and hidden files (a name
/// starting with `.`, such as [`write_whole`]'s partial files) are not counted, and
/// nothing is removed (the folder is the user's): the caller says that these files are
/// there, so that an earlier run's outputs are not taken for this run's. The error is the
/// operating system's, listing `dir`.
pub fn files_not_written(dir: &Path, written: &[PathBuf]) -> std::io::Result<Vec<String>> {
    let mut stale = Vec::new();
    for entry in std::fs::read_dir(dir)? {
        let entry = entry?;
        let name = entry.file_name();
        let regular = entry.file_type().map(|t| t.is_file()).unwrap_or(false);
        if !regular
            || name.as_encoded_bytes().starts_with(b".")
            || written
                .iter()
                .any(|w| w.file_name() == Some(name.as_os_str()))
        {
            continue;
        }
        stale.push(name.to_string_lossy().into_owned());
    }
    stale.sort();
    Ok(stale)
}

/// Writes a tone-mapped 8-bit sRGB PNG.
pub fn write_png(path: &Path, img: &Image, exposure: f32) -> Result<(), String> {
    let mut buf = image::RgbImage::new(img.width, img.height);
    for (i, px) in buf.pixels_mut().enumerate() {
        let p = img.pixels[i];
        *px = image::Rgb([
            tone_map(p[0], exposure),
            tone_map(p[1], exposure),
            tone_map(p[2], exposure),
        ]);
    }
    // the partial file's name ends as `path`'s, so the format follows the extension
    write_whole(path, |partial| {
        buf.save(partial)
            .map_err(|e| format!("{}: {e}", path.display()))
    })
}

/// Writes a file's bytes through [`write_whole`].
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<(), String> {
    write_whole(path, |partial| {
        std::fs::write(partial, bytes).map_err(|e| format!("{}: {e}", path.display()))
    })
}

/// Writes `path` whole or not at all: `write` makes a partial file beside it (a hidden
/// name of this process and write that ends as `path`'s, so a format follows the
/// extension), which is synced and renamed over `path` once written; a failed write (a
/// full disk) removes it, so no truncated file is left under `path` and an earlier one
/// stays as it was.
pub fn write_whole(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), String>,
) -> Result<(), String> {
    let name = path
        .file_name()
        .ok_or_else(|| format!("{}: not a file name", path.display()))?;
    // one partial name per process and write, so that two runs writing the same path
    // (a shared reference cache) do not rename each other's half-written files
    static WRITES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = WRITES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let partial = path.with_file_name(format!(
        ".partial-{}-{n}-{}",
        std::process::id(),
        name.to_string_lossy()
    ));
    let written = write(&partial)
        .and_then(|()| {
            // on the disk before the name points at it
            std::fs::File::open(&partial)
                .and_then(|f| f.sync_all())
                .map_err(|e| format!("{}: {e}", path.display()))
        })
        .and_then(|()| {
            std::fs::rename(&partial, path).map_err(|e| format!("{}: {e}", path.display()))
        });
    if written.is_err() {
        let _ = std::fs::remove_file(&partial);
    }
    written
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file is replaced whole or left as it was, and no partial file stays behind.
    #[test]
    fn files_are_written_whole_or_not_at_all() {
        let dir = std::env::temp_dir().join(format!("caustica-whole-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("stats.json");
        write_file(&path, b"first").unwrap();
        write_file(&path, b"second").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"second");
        // a write that fails half-way (a full disk) leaves the earlier file
        let e = write_whole(&path, |partial| {
            std::fs::write(partial, b"trunc").unwrap();
            Err("No space left on device".into())
        })
        .unwrap_err();
        assert!(e.contains("No space"), "{e}");
        assert_eq!(std::fs::read(&path).unwrap(), b"second");
        let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
        assert_eq!(left.len(), 1, "a partial file was left: {left:?}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// Only regular, visible files that the run did not write are named, sorted; the
    /// folder is left as it was.
    #[test]
    fn files_not_written_are_the_earlier_runs() {
        let dir = std::env::temp_dir().join(format!("caustica-stale-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("references")).unwrap();
        std::fs::write(dir.join("references").join("old.exr"), b"").unwrap();
        for name in [
            "sphere_composite.exr",
            "sphere_composite.png",
            "stats.json",
            "sphere_caustic_atlas.exr",
            "cornell_composite.exr",
            ".partial-1-0-x.exr",
            ".DS_Store",
        ] {
            std::fs::write(dir.join(name), b"").unwrap();
        }
        let written: Vec<PathBuf> = ["sphere_composite.exr", "sphere_composite.png", "stats.json"]
            .iter()
            .map(|n| dir.join(n))
            .collect();
        assert_eq!(
            files_not_written(&dir, &written).unwrap(),
            ["cornell_composite.exr", "sphere_caustic_atlas.exr"]
        );
        // everything was written: nothing to say; nothing was removed
        let mut all = written.clone();
        all.extend(["sphere_caustic_atlas.exr", "cornell_composite.exr"].map(|n| dir.join(n)));
        assert!(files_not_written(&dir, &all).unwrap().is_empty());
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 8);
        assert!(dir.join("references").join("old.exr").exists());
        // a folder that cannot be listed is an error, not a panic
        assert!(files_not_written(&dir.join("missing"), &written).is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn stems_stay_inside_the_folder() {
        for (name, want) in [
            ("sphere", "sphere"),
            ("../x", "_._x"),
            ("/etc/passwd", "_etc_passwd"),
            ("a/b\\c", "a_b_c"),
            ("..", "_."),
            (".hidden", "_hidden"),
            ("nul\0byte", "nul_byte"),
            ("", "scene"),
            ("caf\u{e9}", "caf_"),
        ] {
            assert_eq!(file_stem(name), want, "{name:?}");
        }
        assert_eq!(file_stem(&"x".repeat(300)).len(), 64);
        for name in ["../x", "/abs", "a/../../b", "..\\x"] {
            let p = Path::new("out").join(format!("{}_composite.exr", file_stem(name)));
            assert_eq!(p.parent(), Some(Path::new("out")), "{name}");
        }
    }

    #[test]
    fn identical_images_give_identical_exr_files() {
        let px: Vec<[f32; 4]> = (0..200 * 130)
            .map(|i| [i as f32 * 1e-3, (i % 7) as f32, 0.5, 1.0])
            .collect();
        let img = Image::new(200, 130, px);
        let dir = std::env::temp_dir().join(format!("caustica-exr-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
        write_exr(&a, &img).unwrap();
        write_exr(&b, &img).unwrap();
        assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
        let back = exr::prelude::read_first_rgba_layer_from_file(
            &a,
            |r, _| vec![[0f32; 4]; r.width() * r.height()],
            |px: &mut Vec<[f32; 4]>, p, (r, g, bl, al): (f32, f32, f32, f32)| {
                px[p.y() * 200 + p.x()] = [r, g, bl, al]
            },
        )
        .unwrap();
        assert_eq!(back.layer_data.channel_data.pixels, img.pixels);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
