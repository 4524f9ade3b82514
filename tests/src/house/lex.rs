//! Rust source as the few tokens an import reader needs: identifiers, `::`, string literals
//! (for `#[path = "..."]`) and single punctuation characters. Comments are dropped, so a path
//! in a doc comment or a string is never taken for an import.

/// One token of a source file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Tok {
    /// An identifier or keyword (`r#` stripped from a raw identifier).
    Ident(String),
    /// `::`
    Path,
    /// The contents of a string literal, escapes left as written.
    Str(String),
    /// Any other character outside literals and comments (`{`, `;`, `*`, `#`, `$`, ...).
    Punct(char),
}

/// Splits `src` into tokens; numbers, char literals and lifetimes are dropped.
pub fn tokens(src: &str) -> Vec<Tok> {
    let c: Vec<char> = src.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < c.len() {
        let ch = c[i];
        if ch.is_whitespace() {
            i += 1;
        } else if ch == '/' && c.get(i + 1) == Some(&'/') {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if ch == '/' && c.get(i + 1) == Some(&'*') {
            i = block_comment_end(&c, i);
        } else if ch == '"' {
            let (s, end) = quoted(&c, i + 1);
            out.push(Tok::Str(s));
            i = end;
        } else if let Some((s, end)) = raw_string(&c, i) {
            out.push(Tok::Str(s));
            i = end;
        } else if (ch == 'b' || ch == 'c') && c.get(i + 1) == Some(&'"') {
            let (s, end) = quoted(&c, i + 2);
            out.push(Tok::Str(s));
            i = end;
        } else if ch == '\'' {
            i = quote_end(&c, i);
        } else if ch == 'r'
            && c.get(i + 1) == Some(&'#')
            && c.get(i + 2).is_some_and(|&x| ident_start(x))
        {
            let (s, end) = ident(&c, i + 2);
            out.push(Tok::Ident(s));
            i = end;
        } else if ident_start(ch) {
            let (s, end) = ident(&c, i);
            out.push(Tok::Ident(s));
            i = end;
        } else if ch.is_ascii_digit() {
            while i < c.len() && (c[i].is_ascii_alphanumeric() || c[i] == '_') {
                i += 1;
            }
        } else if ch == ':' && c.get(i + 1) == Some(&':') {
            out.push(Tok::Path);
            i += 2;
        } else {
            out.push(Tok::Punct(ch));
            i += 1;
        }
    }
    out
}

fn ident_start(c: char) -> bool {
    c.is_alphabetic() || c == '_'
}

fn ident(c: &[char], mut i: usize) -> (String, usize) {
    let start = i;
    while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
        i += 1;
    }
    (c[start..i].iter().collect(), i)
}

/// The end of a (nested) block comment that starts at `i`.
fn block_comment_end(c: &[char], mut i: usize) -> usize {
    let mut depth = 0;
    while i < c.len() {
        if c[i] == '/' && c.get(i + 1) == Some(&'*') {
            depth += 1;
            i += 2;
        } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
            depth -= 1;
            i += 2;
            if depth == 0 {
                return i;
            }
        } else {
            i += 1;
        }
    }
    i
}

/// The contents of a `"`-quoted literal whose first character is at `i`, and the index after
/// its closing quote.
fn quoted(c: &[char], mut i: usize) -> (String, usize) {
    let start = i;
    while i < c.len() && c[i] != '"' {
        i += if c[i] == '\\' { 2 } else { 1 };
    }
    let end = i.min(c.len());
    (c[start..end].iter().collect(), end + 1)
}

/// `r"..."`, `r#"..."#`, `br#"..."#` starting at `i`.
fn raw_string(c: &[char], i: usize) -> Option<(String, usize)> {
    let mut j = i;
    if c.get(j) == Some(&'b') || c.get(j) == Some(&'c') {
        j += 1;
    }
    if c.get(j) != Some(&'r') || (j > i && !matches!(c.get(j + 1), Some('#' | '"'))) {
        return None;
    }
    j += 1;
    let mut hashes = 0;
    while c.get(j) == Some(&'#') {
        hashes += 1;
        j += 1;
    }
    if c.get(j) != Some(&'"') {
        return None;
    }
    let start = j + 1;
    let mut k = start;
    while k < c.len() {
        if c[k] == '"' && (1..=hashes).all(|h| c.get(k + h) == Some(&'#')) {
            return Some((c[start..k].iter().collect(), k + 1 + hashes));
        }
        k += 1;
    }
    Some((c[start..].iter().collect(), c.len()))
}

/// Past a char literal (`'a'`, `'\n'`, `'{'`) or a lifetime (`'a`, `'static`) at `i`.
fn quote_end(c: &[char], i: usize) -> usize {
    if c.get(i + 1) == Some(&'\\') {
        let mut j = i + 3;
        while j < c.len() && c[j] != '\'' {
            j += 1;
        }
        return j + 1;
    }
    if c.get(i + 2) == Some(&'\'') {
        return i + 3;
    }
    let mut j = i + 1;
    while j < c.len() && (c[j].is_alphanumeric() || c[j] == '_') {
        j += 1;
    }
    j
}

#[cfg(test)]
mod tests {
    use super::*;

    fn idents(src: &str) -> Vec<String> {
        tokens(src)
            .into_iter()
            .filter_map(|t| match t {
                Tok::Ident(s) => Some(s),
                _ => None,
            })
            .collect()
    }

    #[test]
    fn comments_strings_chars_and_lifetimes_hide_nothing_else() {
        let src = r####"
            // use crate::a;
            /* use crate::b; /* nested */ still */
            let s = "use crate::c; \" quoted";
            let r = r#"use crate::d "#;
            let ch = '{'; let q = '\''; fn f<'a>(x: &'a str) {}
            use crate::e;
        "####;
        let ids = idents(src);
        assert!(
            !ids.iter()
                .any(|s| ["a", "b", "c", "d"].contains(&s.as_str())),
            "{ids:?}"
        );
        assert!(ids.contains(&"e".to_string()));
        let braces = tokens(src)
            .iter()
            .filter(|t| **t == Tok::Punct('{'))
            .count();
        assert_eq!(braces, 1, "only fn f's body opens a brace");
    }

    #[test]
    fn path_separators_and_raw_identifiers() {
        assert_eq!(
            tokens("r#type::x"),
            vec![Tok::Ident("type".into()), Tok::Path, Tok::Ident("x".into())]
        );
    }
}
