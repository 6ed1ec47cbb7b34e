//! Reading input files safely (issue #36): every reader of the workspace (programs, tool
//! tables, scenarios, URDFs, drives files, meshes) opens its file with [`open_regular`],
//! which never blocks and refuses what is not a regular file, naming its kind (a named pipe
//! with no writer would otherwise wait forever, a device never ends); [`read_limited`] reads
//! at most a byte budget; [`xml_too_deep`] bounds the nesting of an XML text before a
//! recursive reader sees it; [`quote`] shortens input quoted in a message.

use std::fs::File;
use std::io::Read;
use std::path::Path;

/// The deepest XML nesting read (elements inside elements): far above any URDF or Collada
/// file (a few dozen levels), far below what would exhaust a reader's stack.
pub const MAX_XML_DEPTH: usize = 256;

/// What a path that is not a regular file is, in words (`"a named pipe (FIFO)"`).
fn kind_of(meta: &std::fs::Metadata) -> Option<&'static str> {
    let t = meta.file_type();
    if t.is_file() {
        return None;
    }
    if t.is_dir() {
        return Some("a folder");
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return Some("a named pipe (FIFO)");
        }
        if t.is_char_device() {
            return Some("a character device");
        }
        if t.is_block_device() {
            return Some("a block device");
        }
        if t.is_socket() {
            return Some("a socket");
        }
    }
    Some("not a regular file")
}

/// Opens `path` for reading without ever blocking (on Unix: `O_NONBLOCK`, so a named pipe
/// with no writer does not wait) and refuses anything but a regular file: a folder, a named
/// pipe, a device or a socket is an error of kind `InvalidInput` saying what it is and that a
/// file is wanted (the caller adds the file's name and what it was read as).
pub fn open_regular(path: &Path) -> std::io::Result<File> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK);
    }
    let file = options.open(path)?;
    if let Some(kind) = kind_of(&file.metadata()?) {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!(
                "it is {kind}, not a regular file (a read would wait or never end): give the \
                 path of a file"
            ),
        ));
    }
    Ok(file)
}

/// Why [`read_limited`] failed.
#[derive(Debug)]
pub enum ReadLimitedError {
    /// The file could not be opened or read, or is not a regular file ([`open_regular`]).
    Io(std::io::Error),
    /// The file holds more than the limit; `size` is its size when the file system knows it.
    TooLarge {
        /// The file's size (bytes), if known.
        size: Option<u64>,
    },
}

/// Reads the regular file `path` ([`open_regular`]) whole, refusing more than `limit` bytes
/// (reading stops one byte past the limit).
pub fn read_limited(path: &Path, limit: u64) -> Result<Vec<u8>, ReadLimitedError> {
    let file = open_regular(path).map_err(ReadLimitedError::Io)?;
    let size = file.metadata().ok().map(|m| m.len());
    let mut bytes = Vec::new();
    file.take(limit.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(ReadLimitedError::Io)?;
    if bytes.len() as u64 > limit {
        return Err(ReadLimitedError::TooLarge { size });
    }
    Ok(bytes)
}

/// The first place (1-based line and column of the opening `<`) where the elements of the
/// XML `text` nest deeper than `limit`, if any. A byte scan, no recursion: comments,
/// processing instructions, declarations and CDATA sections are skipped, `<a/>` does not
/// nest, quoted attribute values may hold `>`.
pub fn xml_too_deep(text: &str, limit: usize) -> Option<(usize, usize)> {
    let b = text.as_bytes();
    let mut depth = 0usize;
    let mut i = 0;
    while let Some(off) = b[i..].iter().position(|&c| c == b'<') {
        let start = i + off;
        let rest = &b[start..];
        let skip_to = |end: &[u8]| {
            rest.windows(end.len())
                .position(|w| w == end)
                .map_or(b.len(), |p| start + p + end.len())
        };
        if rest.starts_with(b"<!--") {
            i = skip_to(b"-->");
        } else if rest.starts_with(b"<![CDATA[") {
            i = skip_to(b"]]>");
        } else if rest.starts_with(b"<?") {
            i = skip_to(b"?>");
        } else if rest.starts_with(b"<!") {
            i = skip_to(b">");
        } else if rest.starts_with(b"</") {
            depth = depth.saturating_sub(1);
            i = skip_to(b">");
        } else {
            // An opening tag: its end, past quoted attribute values.
            let mut j = start + 1;
            let mut quote: Option<u8> = None;
            while j < b.len() {
                match (quote, b[j]) {
                    (None, b'"' | b'\'') => quote = Some(b[j]),
                    (Some(q), c) if c == q => quote = None,
                    (None, b'>') => break,
                    _ => {}
                }
                j += 1;
            }
            if j >= b.len() || b[j - 1] != b'/' {
                depth += 1;
                if depth > limit {
                    let line_start = b[..start]
                        .iter()
                        .rposition(|&c| c == b'\n')
                        .map_or(0, |p| p + 1);
                    let line = b[..start].iter().filter(|&&c| c == b'\n').count() + 1;
                    let column = text[line_start..start].chars().count() + 1;
                    return Some((line, column));
                }
            }
            i = (j + 1).min(b.len());
        }
        if i >= b.len() {
            break;
        }
    }
    None
}

/// The most characters of input a message quotes ([`quote`]).
pub const QUOTE_CHARS: usize = 40;

/// `s` as quoted in a message: whole when at most `max` characters, else its first `max`
/// characters followed by `… (N characters)`, so that a huge line of input never makes a
/// huge message.
pub fn quote(s: &str, max: usize) -> String {
    let n = s.chars().count();
    if n <= max {
        return s.to_string();
    }
    let head: String = s.chars().take(max).collect();
    format!("{head}… ({n} characters)")
}

/// The longest line of a message kept whole by [`for_reader`] (characters).
pub(crate) const MESSAGE_LINE_CHARS: usize = 1000;

/// A message made readable (issue #36), as the command and the Python bindings show it: a
/// number written with more than 19 digits (`1e300` printed in full, a saturated count) is
/// written in scientific notation with four significant digits (`1.000e300`), and a line
/// longer than `MESSAGE_LINE_CHARS` (1000) is cut there with its length said, so that input
/// quoted whole (a 3 MB TOML line) never makes a huge message.
pub fn for_reader(message: &str) -> String {
    let mut out = String::with_capacity(message.len().min(4096));
    for (i, line) in message.split('\n').enumerate() {
        if i > 0 {
            out.push('\n');
        }
        out.push_str(&quote(&short_numbers(line), MESSAGE_LINE_CHARS));
    }
    out
}

/// `line` with each number of more than 19 digits (not inside a word or a path) written as
/// `{:.3e}`.
fn short_numbers(line: &str) -> String {
    let b = line.as_bytes();
    let mut out = String::with_capacity(line.len());
    let mut i = 0;
    let mut copied = 0;
    while i < b.len() {
        let word = |c: u8| c.is_ascii_alphanumeric() || b"_/.-".contains(&c);
        // A minus sign counts as a boundary when it starts a number ("(-1452…, 0)"), not
        // inside a word ("run-2026…").
        let boundary =
            i == 0 || !word(b[i - 1]) || (b[i - 1] == b'-' && (i == 1 || !word(b[i - 2])));
        if !(boundary && b[i].is_ascii_digit()) {
            i += 1;
            continue;
        }
        let start = i;
        while i < b.len() && (b[i].is_ascii_digit() || b[i] == b'.') {
            i += 1;
        }
        let token = &line[start..i];
        let digits = token.bytes().filter(u8::is_ascii_digit).count();
        let ends_word = i < b.len() && (b[i].is_ascii_alphabetic() || b[i] == b'_');
        if digits > 19 && !ends_word && token.matches('.').count() <= 1 {
            if let Ok(v) = token.parse::<f64>() {
                out.push_str(&line[copied..start]);
                out.push_str(&format!("{v:.3e}"));
                copied = i;
            }
        }
    }
    out.push_str(&line[copied..]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depth_is_counted_past_comments_self_closing_tags_and_quoted_brackets() {
        let t = "<?xml version=\"1.0\"?>\n<!-- <a><a><a> -->\n<r a=\"x>y\"><b/><c><d/></c></r>";
        assert_eq!(xml_too_deep(t, 2), None);
        assert_eq!(xml_too_deep(t, 1), Some((3, 16)));
        let deep = "<a>".repeat(300) + &"</a>".repeat(300);
        assert_eq!(xml_too_deep(&deep, 300), None);
        assert_eq!(xml_too_deep(&deep, 299), Some((1, 299 * 3 + 1)));
        // Siblings do not add up.
        let wide = "<r>".to_string() + &"<a></a>".repeat(1000) + "</r>";
        assert_eq!(xml_too_deep(&wide, 2), None);
    }

    #[test]
    fn messages_write_huge_numbers_short_and_cut_huge_lines() {
        let e300 = format!("ts = 1{}.0 s, count {}", "0".repeat(300), u64::MAX);
        assert_eq!(for_reader(&e300), "ts = 1.000e300 s, count 1.845e19");
        let tiny = format!("ts = 0.{}1", "0".repeat(299));
        assert_eq!(for_reader(&tiny), "ts = 1.000e-300");
        // Ordinary numbers, words and paths with digits stay as they are.
        let neg = format!("flange at (-1{}.0000, 0.0000)", "4".repeat(250));
        assert_eq!(for_reader(&neg), "flange at (-1.444e250, 0.0000)");
        let plain = "line 12, column 3: 0.01 s; run-20261203173811123456/x1234567890123456789012";
        assert_eq!(for_reader(plain), plain);
        let huge = format!("1 | x = \"{}\"\nsecond line", "a".repeat(3_000_000));
        let m = for_reader(&huge);
        assert!(
            m.len() < 1100 && m.ends_with("characters)\nsecond line"),
            "{m}"
        );
    }

    #[test]
    fn a_long_quote_is_cut_and_says_its_length() {
        assert_eq!(quote("short", 40), "short");
        let q = quote(&"é".repeat(100), 10);
        assert_eq!(q, format!("{}… (100 characters)", "é".repeat(10)));
    }

    #[cfg(unix)]
    #[test]
    fn a_fifo_a_folder_and_a_device_are_refused_without_waiting() {
        let dir = std::env::temp_dir().join(format!("ofmpc-input-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let fifo = dir.join("fifo");
        let _ = std::fs::remove_file(&fifo);
        assert!(std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success());
        for (p, kind) in [
            (fifo.as_path(), "a named pipe (FIFO)"),
            (dir.as_path(), "a folder"),
            (Path::new("/dev/null"), "a character device"),
        ] {
            let e = open_regular(p).unwrap_err();
            assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput, "{p:?}");
            assert!(e.to_string().contains(kind), "{p:?}: {e}");
        }
        let f = dir.join("f");
        std::fs::write(&f, b"abc").unwrap();
        assert_eq!(read_limited(&f, 3).unwrap(), b"abc");
        assert!(matches!(
            read_limited(&f, 2),
            Err(ReadLimitedError::TooLarge { size: Some(3) })
        ));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
