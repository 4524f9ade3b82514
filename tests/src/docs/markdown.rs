//! What the docs test reads from one markdown file: code spans, the lines of fenced code
//! blocks, link targets and heading anchors, each with its line number.
//!
//! Not a full CommonMark parser: fences (backticks or tildes), code spans (which may run over
//! line breaks but not over a blank line), inline links and images `[text](target)` and
//! reference definitions `[label]: target` are what the docs use. Indented code blocks are not
//! recognised; the docs fence their code.

/// A code span's text (line breaks inside it read as spaces), with the line it starts on.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Span {
    /// 1-based line number.
    pub line: usize,
    /// The text between the backticks, trimmed.
    pub text: String,
}

/// One line inside a fenced code block.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FenceLine {
    /// 1-based line number.
    pub line: usize,
    /// The fence's info string (`sh`, `toml`, `text`, or empty).
    pub lang: String,
    /// The line as written.
    pub text: String,
}

/// A link or image target outside code.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Link {
    /// 1-based line number.
    pub line: usize,
    /// The target as written (`../perf/perf.md#decision-round`).
    pub target: String,
}

/// Everything the checks need from one file.
#[derive(Debug, Default)]
pub struct Scan {
    /// Code spans outside fences.
    pub spans: Vec<Span>,
    /// Lines of fenced code blocks.
    pub fences: Vec<FenceLine>,
    /// Link and image targets outside code.
    pub links: Vec<Link>,
    /// The anchors GitHub gives the headings, in order (duplicates numbered `-1`, `-2`, ...).
    pub anchors: Vec<String>,
}

/// Scans one markdown text.
pub fn scan(text: &str) -> Scan {
    let mut out = Scan::default();
    let mut fence: Option<(char, usize, String)> = None;
    // The current block of prose: (line number, line) pairs up to the next blank line.
    let mut block: Vec<(usize, &str)> = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let n = i + 1;
        let trimmed = line.trim_start();
        if let Some((ch, len, lang)) = &fence {
            if closes(trimmed, *ch, *len) {
                fence = None;
            } else {
                out.fences.push(FenceLine {
                    line: n,
                    lang: lang.clone(),
                    text: line.to_string(),
                });
            }
            continue;
        }
        if let Some((ch, len)) = opens(trimmed) {
            prose(&block, &mut out);
            block.clear();
            let lang = trimmed[len..].trim().to_string();
            fence = Some((ch, len, lang));
            continue;
        }
        if trimmed.is_empty() {
            prose(&block, &mut out);
            block.clear();
            continue;
        }
        if let Some(title) = heading(trimmed) {
            prose(&block, &mut out);
            block.clear();
            let base = slug(title);
            let same = out
                .anchors
                .iter()
                .filter(|a| **a == base || numbered(a, &base))
                .count();
            out.anchors.push(if same == 0 {
                base
            } else {
                format!("{base}-{same}")
            });
        }
        block.push((n, line));
    }
    prose(&block, &mut out);
    out
}

/// Whether `a` is `base-K` for a number K.
fn numbered(a: &str, base: &str) -> bool {
    a.strip_prefix(base)
        .and_then(|r| r.strip_prefix('-'))
        .is_some_and(|k| !k.is_empty() && k.bytes().all(|b| b.is_ascii_digit()))
}

/// A fence opening: three or more backticks or tildes.
fn opens(line: &str) -> Option<(char, usize)> {
    let ch = line.chars().next().filter(|c| *c == '`' || *c == '~')?;
    let len = line.chars().take_while(|c| *c == ch).count();
    (len >= 3).then_some((ch, len))
}

/// Whether `line` closes a fence of `len` `ch`s.
fn closes(line: &str, ch: char, len: usize) -> bool {
    let run = line.chars().take_while(|c| *c == ch).count();
    run >= len && line[run * ch.len_utf8()..].trim().is_empty()
}

/// The title of an ATX heading.
fn heading(line: &str) -> Option<&str> {
    let level = line.bytes().take_while(|b| *b == b'#').count();
    if !(1..=6).contains(&level) {
        return None;
    }
    let rest = &line[level..];
    rest.starts_with(' ')
        .then(|| rest.trim().trim_end_matches('#').trim())
}

/// GitHub's anchor for a heading: link targets and emphasis reduced to their text, lower
/// case, every character but letters, digits, `-`, `_` and spaces dropped, spaces to `-`.
pub fn slug(title: &str) -> String {
    let mut text = String::new();
    let mut rest = title;
    // `[text](target)` reads as `text`.
    while let Some(open) = rest.find('[') {
        let close = rest[open..].find("](").map(|c| open + c);
        let end = close.and_then(|c| rest[c..].find(')').map(|e| c + e));
        match (close, end) {
            (Some(c), Some(e)) => {
                text.push_str(&rest[..open]);
                text.push_str(&rest[open + 1..c]);
                rest = &rest[e + 1..];
            }
            _ => break,
        }
    }
    text.push_str(rest);
    text.to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || *c == '-' || *c == '_' || *c == ' ')
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// Code spans and links of one block of prose.
fn prose(block: &[(usize, &str)], out: &mut Scan) {
    if block.is_empty() {
        return;
    }
    // The block as one string, and the line each byte is on.
    let mut text = String::new();
    let mut lines = Vec::new();
    for (n, l) in block {
        text.push_str(l);
        text.push('\n');
        lines.resize(text.len(), *n);
    }
    let line_at = |offset: usize| lines[offset.min(lines.len() - 1)];
    // `code` is the block with every code span blanked, for the link search.
    let mut code = text.clone().into_bytes();
    let bytes = text.as_bytes();
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] != b'`' {
            i += 1;
            continue;
        }
        let run = bytes[i..].iter().take_while(|b| **b == b'`').count();
        match closing_run(bytes, i + run, run) {
            Some(end) => {
                let inner = &text[i + run..end];
                out.spans.push(Span {
                    line: line_at(i),
                    text: inner.replace('\n', " ").trim().to_string(),
                });
                for b in &mut code[i..end + run] {
                    if *b != b'\n' {
                        *b = b' ';
                    }
                }
                i = end + run;
            }
            None => i += run,
        }
    }
    let code = String::from_utf8(code).expect("blanking replaced whole ASCII bytes only");
    links(&code, &line_at, out);
}

/// The start of the next run of exactly `run` backticks at or after `from`.
fn closing_run(bytes: &[u8], from: usize, run: usize) -> Option<usize> {
    let mut j = from;
    while j < bytes.len() {
        if bytes[j] == b'`' {
            let len = bytes[j..].iter().take_while(|b| **b == b'`').count();
            if len == run {
                return Some(j);
            }
            j += len;
        } else {
            j += 1;
        }
    }
    None
}

/// Inline link targets `](target)` and reference definitions `[label]: target`.
fn links(text: &str, line_at: &dyn Fn(usize) -> usize, out: &mut Scan) {
    let mut from = 0;
    while let Some(k) = text[from..].find("](") {
        let start = from + k + 2;
        let Some(len) = text[start..].find(')') else {
            break;
        };
        let inside = text[start..start + len].trim();
        // `(target "title")`: the title is not part of the target.
        let target = inside.split_whitespace().next().unwrap_or("");
        let target = target.trim_start_matches('<').trim_end_matches('>');
        if !target.is_empty() {
            out.links.push(Link {
                line: line_at(start),
                target: target.to_string(),
            });
        }
        from = start + len;
    }
    let mut offset = 0;
    for l in text.split_inclusive('\n') {
        let t = l.trim_start();
        if let Some(rest) = t.strip_prefix('[') {
            if let Some(close) = rest.find("]:") {
                let target = rest[close + 2..].split_whitespace().next().unwrap_or("");
                if !target.is_empty() && !rest[..close].contains('[') {
                    out.links.push(Link {
                        line: line_at(offset),
                        target: target.to_string(),
                    });
                }
            }
        }
        offset += l.len();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spans_may_run_over_a_line_break_and_links_inside_code_are_not_links() {
        let s = scan("a `hnav log\nverify` b\n\n`[x](nowhere.md)` [y](docs/a.md#b)\n");
        assert_eq!(
            s.spans[0],
            Span {
                line: 1,
                text: "hnav log verify".into()
            }
        );
        assert_eq!(s.links.len(), 1);
        assert_eq!(s.links[0].target, "docs/a.md#b");
        assert_eq!(s.links[0].line, 4);
    }

    #[test]
    fn fences_keep_their_language_and_hide_their_content_from_prose() {
        let s = scan("```sh\nhnav ps # `x`\n```\n\n[r]: ../README.md\n");
        assert_eq!(s.fences.len(), 1);
        assert_eq!(s.fences[0].lang, "sh");
        assert_eq!(s.fences[0].line, 2);
        assert!(s.spans.is_empty());
        assert_eq!(s.links[0].target, "../README.md");
        assert_eq!(s.links[0].line, 5);
    }

    #[test]
    fn anchors_are_githubs() {
        let s = scan("# A\n## Dense swarms: LaCAM (`rules = \"lacam\"`)\n## A\n## A\n");
        assert_eq!(
            s.anchors,
            ["a", "dense-swarms-lacam-rules--lacam", "a-1", "a-2"]
        );
        assert_eq!(
            slug("Experiment `pso`: paired steps"),
            "experiment-pso-paired-steps"
        );
        assert_eq!(slug("Tables 3-8, 3-9"), "tables-3-8-3-9");
    }
}
