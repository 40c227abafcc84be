//! Text for messages: untrusted content and paths quoted short and safe.
//!
//! Every message that quotes a file's content or a path goes through
//! [`excerpt`] or [`shown`], so a forged file cannot put terminal escapes or
//! bidirectional overrides into a terminal or a log.

use std::path::Path;

/// Characters of file content a message may quote.
pub const EXCERPT_CHARS: usize = 48;

/// A short, safe excerpt of untrusted text for a message: at most
/// `max_chars` characters (then `…`), with control characters (including
/// terminal escapes and NUL) and bidirectional overrides escaped.
pub fn excerpt(text: &str, max_chars: usize) -> String {
    let mut out = String::new();
    for (i, c) in text.chars().enumerate() {
        if i == max_chars {
            out.push('…');
            break;
        }
        let bidi = matches!(c, '\u{200E}' | '\u{200F}' | '\u{202A}'..='\u{202E}' | '\u{2066}'..='\u{2069}');
        if c.is_control() || bidi {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    out
}

/// A path for a message: [`excerpt`] of its text, at most 200 characters.
pub fn shown(path: &Path) -> String {
    excerpt(&path.to_string_lossy(), 200)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn excerpts_are_short_and_escaped() {
        assert_eq!(excerpt("abc", 10), "abc");
        assert_eq!(excerpt("abcdef", 3), "abc…");
        assert_eq!(excerpt("a\u{1b}[2Jb\0", 10), "a\\u{1b}[2Jb\\u{0}");
        assert_eq!(excerpt("x\u{202E}y", 10), "x\\u{202e}y");
        assert_eq!(excerpt("µ ok", 10), "µ ok");
    }
}
