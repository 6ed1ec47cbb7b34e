//! Robot description files read with a size limit (issue #22 item 15): a
//! `/dev/zero` or a runaway file given as a URDF or a drives file is never
//! read whole, and text that is not UTF-8 is an error naming the byte.

use super::error::ModelError;
use std::io::Read;
use std::path::Path;

/// The largest URDF read (bytes): 64 MiB, far above any robot description (a 300-joint
/// URDF with every element written out is a few MiB; meshes are separate files).
pub const MAX_URDF_BYTES: u64 = 64 << 20;

/// The largest drives file read (bytes): 4 MiB (a few lines per joint).
pub const MAX_DRIVES_BYTES: u64 = 4 << 20;

/// Reads the text file `path` of at most `limit` bytes, as `what` (`"a URDF"`): reading
/// stops one byte past the limit ([`ModelError::FileTooLarge`], with the file's size when
/// the file system knows it); bytes that are not UTF-8 are [`ModelError::NotUtf8`] with
/// their offset, line and column.
pub(crate) fn read_text_limited(
    path: &Path,
    limit: u64,
    what: &'static str,
) -> Result<String, ModelError> {
    let name = || path.display().to_string();
    let io = |e: std::io::Error| ModelError::Io {
        path: name(),
        message: e.to_string(),
    };
    let file = std::fs::File::open(path).map_err(io)?;
    let size = file
        .metadata()
        .ok()
        .filter(|m| m.is_file())
        .map(|m| m.len());
    let mut bytes = Vec::new();
    file.take(limit.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(io)?;
    if bytes.len() as u64 > limit {
        return Err(ModelError::FileTooLarge {
            path: name(),
            what,
            size,
            limit,
        });
    }
    String::from_utf8(bytes).map_err(|e| {
        let offset = e.utf8_error().valid_up_to();
        let b = e.as_bytes();
        let line_start = b[..offset]
            .iter()
            .rposition(|&c| c == b'\n')
            .map_or(0, |i| i + 1);
        ModelError::NotUtf8 {
            path: name(),
            offset,
            line: b[..offset].iter().filter(|&&c| c == b'\n').count() + 1,
            column: offset - line_start + 1,
            byte: b.get(offset).copied().unwrap_or(0),
            utf16: b.starts_with(&[0xff, 0xfe]) || b.starts_with(&[0xfe, 0xff]),
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_past_the_limit_is_refused_with_its_size_and_the_limit() {
        let dir = std::env::temp_dir().join(format!("ofmpc-read-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("big.urdf");
        std::fs::write(&p, vec![b' '; 2049]).unwrap();
        let e = read_text_limited(&p, 2048, "a URDF").unwrap_err();
        assert!(
            matches!(
                e,
                ModelError::FileTooLarge {
                    size: Some(2049),
                    limit: 2048,
                    ..
                }
            ),
            "{e:?}"
        );
        let text = e.to_string();
        assert!(
            text.contains("2049 bytes") && text.contains("limit of 2048 bytes"),
            "{text}"
        );
        assert_eq!(read_text_limited(&p, 2049, "a URDF").unwrap().len(), 2049);
        std::fs::write(&p, b"<robot>\n caf\xe9").unwrap();
        let e = read_text_limited(&p, 2048, "a URDF").unwrap_err();
        assert_eq!(
            e,
            ModelError::NotUtf8 {
                path: p.display().to_string(),
                offset: 12,
                line: 2,
                column: 5,
                byte: 0xe9,
                utf16: false
            }
        );
        std::fs::remove_dir_all(&dir).unwrap();
        if Path::new("/dev/zero").exists() {
            let e = read_text_limited(Path::new("/dev/zero"), 1 << 20, "a URDF").unwrap_err();
            assert!(
                matches!(e, ModelError::FileTooLarge { size: None, .. }),
                "{e:?}"
            );
        }
    }
}
