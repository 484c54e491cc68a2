//! Text from input made safe to print: a scene's strings, a file's grid or map-type names and the messages that
//! quote them reach a terminal, where an escape sequence would clear the screen or recolour it, and a megabyte
//! token would bury everything else.

use std::fmt::Write;

/// The most characters of one message printed; the rest is counted, not shown.
pub const MAX_MESSAGE_CHARS: usize = 4096;

/// `s` with every control character but newline and tab written as its escape (`\u{1b}`), cut to `max`
/// characters with the count of those left out.
pub fn printable(s: &str, max: usize) -> String {
    let mut out = String::with_capacity(s.len().min(max) + 16);
    for (n, c) in s.chars().enumerate() {
        if n == max {
            let rest = s.chars().count() - n;
            write!(out, "… ({rest} more characters)").ok();
            break;
        }
        if c.is_control() && c != '\n' && c != '\t' {
            write!(out, "{}", c.escape_unicode()).ok();
        } else {
            out.push(c);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::printable;

    #[test]
    fn control_characters_are_escaped_and_long_text_cut() {
        assert_eq!(
            printable("map \u{1b}[2J\u{1b}[31mred\r\n\tok", 100),
            "map \\u{1b}[2J\\u{1b}[31mred\\u{d}\n\tok"
        );
        assert_eq!(printable("abcdef", 4), "abcd… (2 more characters)");
        assert_eq!(printable("plain", 4096), "plain");
    }
}
