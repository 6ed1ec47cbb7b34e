//! Invisible characters in program text, and how messages show them. A leaf of the reader.

/// Is `c` a character that shows as nothing or as a blank (control characters, no-break and
/// zero-width spaces, byte-order marks, directional marks)?
pub(super) fn is_invisible(c: char) -> bool {
    c.is_control()
        || matches!(c, '\u{a0}' | '\u{ad}' | '\u{2000}'..='\u{200f}' | '\u{2028}'..='\u{202f}' | '\u{205f}'..='\u{206f}' | '\u{feff}')
}

/// `s` with invisible characters written as `\u{…}` escapes.
pub(super) fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        if is_invisible(c) && c != ' ' {
            out.push_str(&format!("\\u{{{:x}}}", c as u32));
        } else {
            out.push(c);
        }
    }
    out
}
