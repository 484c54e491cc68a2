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

/// clap's error as one line: its first paragraph (the problem, and the arguments it names on the lines below)
/// and its usage line — "the following required arguments were not provided: <SCENE> <REFERENCE> (usage:
/// firemedium compare <SCENE> <REFERENCE> <IMAGES>...)" —, made [`printable`]: clap echoes the value a user
/// gave, and an escape sequence in it must reach the terminal as text.
pub fn one_line(text: &str) -> String {
    let mut lines = text.lines();
    let mut out: Vec<&str> = Vec::new();
    for l in lines.by_ref() {
        if l.trim().is_empty() {
            break;
        }
        out.push(l.trim());
    }
    let mut msg = out.join(" ");
    msg = msg.trim_start_matches("error: ").to_string();
    if msg.is_empty() {
        msg = "invalid arguments".into();
    }
    if let Some(usage) = lines.find_map(|l| l.trim().strip_prefix("Usage: ")) {
        msg += &format!(" (usage: {usage}; see --help)");
    }
    printable(&msg, MAX_MESSAGE_CHARS)
}

#[cfg(test)]
mod tests {
    #[test]
    fn clap_errors_become_one_line_naming_the_arguments_and_the_usage() {
        let text = "error: the following required arguments were not provided:\n  <SCENE>\n  <REFERENCE>\n\nUsage: firemedium compare <SCENE> <REFERENCE> <IMAGES>...\n\nFor more information, try '--help'.\n";
        assert_eq!(
            super::one_line(text),
            "the following required arguments were not provided: <SCENE> <REFERENCE> (usage: firemedium compare <SCENE> <REFERENCE> <IMAGES>...; see --help)"
        );
    }

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
