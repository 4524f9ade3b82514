//! What one source file says about modules: the modules it declares (in other files or inline),
//! the names it defines, its `use` trees, and the paths in its code that may name an item of
//! its own crate. Nothing is resolved here; [`super::tree`] does that across files.

use super::lex::{tokens, Tok};

/// One module of a file: the file's own (scope 0) or an inline `mod name { ... }`.
#[derive(Debug, Default)]
pub struct Scope {
    /// The inline module's name (empty for scope 0).
    pub name: String,
    /// The scope it is declared in (scope 0 for itself).
    pub parent: usize,
    /// Names of items defined at its top level (`fn`, `struct`, `enum`, `macro_rules!`, ...).
    pub defs: Vec<String>,
    /// Compiled for tests only (`#[cfg(test)]` on it or on a scope around it).
    pub test: bool,
}

/// What a `use` leaf brings into scope.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Bind {
    /// `path` (or `path as name`) binds `name`; `_` for an anonymous trait import.
    Name(String),
    /// `path::*`
    Glob,
}

/// One leaf of a `use` tree, its prefixes joined: `use a::{b, c::*}` gives `a::b` and `a::c::*`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UseLeaf {
    /// The scope the `use` is written in.
    pub scope: usize,
    /// Written at the scope's top level (not inside a function or an `impl`): the binding is
    /// then an item of the module, visible to others (`super::name`, re-exports).
    pub item: bool,
    /// The path's segments; a leading `::` is kept as a segment `::`.
    pub path: Vec<String>,
    /// What it binds.
    pub bind: Bind,
    /// `pub use` (any visibility): a re-export, not a use of the item by this file.
    pub export: bool,
    /// In test-only code: a `#[cfg(test)]` use or scope.
    pub test: bool,
}

/// A `mod name;` declaration: a module in another file.
#[derive(Debug)]
pub struct ModDecl {
    /// The scope that declares it.
    pub scope: usize,
    /// Its name.
    pub name: String,
    /// A `#[path = "..."]` attribute on it.
    pub path_attr: Option<String>,
    /// Test-only: `#[cfg(test)]` on it or on a scope around it.
    pub test: bool,
}

/// A path in code (not in a `use`) of two or more segments, with the scope it is written in.
#[derive(Debug)]
pub struct CodePath {
    /// The scope it is written in.
    pub scope: usize,
    /// Its segments (`$crate` as `crate`).
    pub segs: Vec<String>,
}

/// One source file, read.
#[derive(Debug, Default)]
pub struct Parsed {
    /// Scope 0 is the file's module; the others are its inline modules.
    pub scopes: Vec<Scope>,
    /// Modules declared in other files.
    pub mods: Vec<ModDecl>,
    /// Every `use` leaf.
    pub uses: Vec<UseLeaf>,
    /// Every multi-segment path in code.
    pub paths: Vec<CodePath>,
    /// `#[macro_export] macro_rules!` names: items of the crate root, wherever they are written.
    pub exported_macros: Vec<String>,
}

const ITEM_KEYWORDS: [&str; 8] = [
    "fn", "struct", "enum", "trait", "type", "const", "static", "union",
];

/// Reads `src`.
pub fn parse(src: &str) -> Parsed {
    let t = tokens(src);
    let mut p = Parsed {
        scopes: vec![Scope::default()],
        ..Parsed::default()
    };
    // (scope, brace depth of its body)
    let mut stack: Vec<(usize, usize)> = vec![(0, 0)];
    let mut depth = 0;
    let mut inline_next: Option<usize> = None;
    let mut path_attr: Option<String> = None;
    let mut macro_export = false;
    let mut cfg_test = false;
    let mut i = 0;
    while i < t.len() {
        let (scope, body) = *stack.last().expect("the file's scope is never popped");
        let top = depth == body;
        match &t[i] {
            Tok::Punct('{') => {
                depth += 1;
                if let Some(s) = inline_next.take() {
                    stack.push((s, depth));
                }
                i += 1;
            }
            Tok::Punct('}') => {
                if stack.len() > 1 && depth == body {
                    stack.pop();
                }
                depth = depth.saturating_sub(1);
                (path_attr, macro_export, cfg_test) = (None, false, false);
                i += 1;
            }
            Tok::Punct(';') => {
                (path_attr, macro_export, cfg_test) = (None, false, false);
                i += 1;
            }
            Tok::Punct('#') => {
                let (end, attr) = attribute(&t, i);
                path_attr = attr.path.or(path_attr);
                macro_export |= attr.macro_export;
                cfg_test |= attr.cfg_test;
                i = end;
            }
            Tok::Ident(kw) if kw == "mod" => match (t.get(i + 1), t.get(i + 2)) {
                (Some(Tok::Ident(name)), Some(Tok::Punct(';'))) => {
                    let path_attr = path_attr.take();
                    let test = cfg_test || p.scopes[scope].test;
                    p.mods.push(ModDecl {
                        scope,
                        name: name.clone(),
                        path_attr,
                        test,
                    });
                    i += 2;
                }
                (Some(Tok::Ident(name)), Some(Tok::Punct('{'))) => {
                    let test = cfg_test || p.scopes[scope].test;
                    p.scopes.push(Scope {
                        name: name.clone(),
                        parent: scope,
                        defs: Vec::new(),
                        test,
                    });
                    cfg_test = false;
                    inline_next = Some(p.scopes.len() - 1);
                    i += 2;
                }
                _ => i += 1,
            },
            Tok::Ident(kw) if kw == "use" && t.get(i + 1) != Some(&Tok::Punct('<')) => {
                let mut pos = i + 1;
                let mut leaves = Vec::new();
                use_tree(&t, &mut pos, Vec::new(), false, &mut leaves);
                let export = visible(&t, i);
                let test = cfg_test || p.scopes[scope].test;
                p.uses
                    .extend(leaves.into_iter().map(|(path, bind)| UseLeaf {
                        scope,
                        item: top,
                        path,
                        bind,
                        export,
                        test,
                    }));
                i = pos;
            }
            Tok::Ident(kw) if kw == "macro_rules" => {
                if let (Some(Tok::Punct('!')), Some(Tok::Ident(name))) =
                    (t.get(i + 1), t.get(i + 2))
                {
                    if macro_export {
                        p.exported_macros.push(name.clone());
                    } else if top {
                        p.scopes[scope].defs.push(name.clone());
                    }
                }
                i += 1;
            }
            Tok::Ident(kw) if top && ITEM_KEYWORDS.contains(&kw.as_str()) => {
                if let Some(Tok::Ident(name)) = t.get(i + 1) {
                    if !matches!(name.as_str(), "fn" | "unsafe" | "async" | "extern") {
                        p.scopes[scope].defs.push(name.clone());
                    }
                }
                i += 1;
            }
            Tok::Ident(_) | Tok::Punct('$') => {
                let global = i > 0 && t[i - 1] == Tok::Path;
                let (segs, end) = code_path(&t, i);
                if !global && segs.len() >= 2 {
                    p.paths.push(CodePath { scope, segs });
                }
                i = end;
            }
            _ => i += 1,
        }
    }
    p
}

/// What an attribute says that matters here.
#[derive(Default)]
struct Attr {
    path: Option<String>,
    macro_export: bool,
    cfg_test: bool,
}

/// An attribute `#[...]` or `#![...]` at `i`: the index after it, and what it says.
fn attribute(t: &[Tok], i: usize) -> (usize, Attr) {
    let mut j = i + 1;
    if t.get(j) == Some(&Tok::Punct('!')) {
        j += 1;
    }
    if t.get(j) != Some(&Tok::Punct('[')) {
        return (i + 1, Attr::default());
    }
    let start = j + 1;
    let mut level = 0;
    while j < t.len() {
        match t[j] {
            Tok::Punct('[') => level += 1,
            Tok::Punct(']') => {
                level -= 1;
                if level == 0 {
                    break;
                }
            }
            _ => {}
        }
        j += 1;
    }
    let body = &t[start..j.min(t.len())];
    let path = match body {
        [Tok::Ident(k), Tok::Punct('='), Tok::Str(s)] if k == "path" => Some(s.clone()),
        _ => None,
    };
    let ident = |k: usize, s: &str| matches!(body.get(k), Some(Tok::Ident(x)) if x == s);
    let attr = Attr {
        path,
        macro_export: ident(0, "macro_export"),
        cfg_test: ident(0, "cfg") && ident(2, "test") && body.len() == 4,
    };
    (j + 1, attr)
}

/// Whether the item whose keyword is at `i` is `pub` or `pub(...)`.
fn visible(t: &[Tok], i: usize) -> bool {
    let mut j = i;
    if j > 0 && t[j - 1] == Tok::Punct(')') {
        while j > 0 && t[j - 1] != Tok::Punct('(') {
            j -= 1;
        }
        j = j.saturating_sub(1);
    }
    j > 0 && t[j - 1] == Tok::Ident("pub".into())
}

/// The path `a::b::c` (or `$crate::...`) starting at `i`, and the index after it.
fn code_path(t: &[Tok], i: usize) -> (Vec<String>, usize) {
    let mut segs = Vec::new();
    let mut j = i;
    if t[j] == Tok::Punct('$') {
        match t.get(j + 1) {
            Some(Tok::Ident(k)) if k == "crate" => j += 1,
            _ => return (segs, i + 1),
        }
    }
    while let Some(Tok::Ident(s)) = t.get(j) {
        segs.push(s.clone());
        j += 1;
        if t.get(j) == Some(&Tok::Path) && matches!(t.get(j + 1), Some(Tok::Ident(_))) {
            j += 1;
        } else {
            break;
        }
    }
    (segs, j.max(i + 1))
}

/// One use tree at `pos` (after `use`, or inside braces), its leaves appended to `out`; `pos`
/// ends after the tree (at the `;` for a whole `use`).
fn use_tree(
    t: &[Tok],
    pos: &mut usize,
    mut path: Vec<String>,
    braced: bool,
    out: &mut Vec<(Vec<String>, Bind)>,
) {
    if t.get(*pos) == Some(&Tok::Path) {
        path.push("::".into());
        *pos += 1;
    }
    loop {
        match t.get(*pos) {
            Some(Tok::Ident(s))
                if s == "self"
                    && braced
                    && !path.is_empty()
                    && t.get(*pos + 1) != Some(&Tok::Path) =>
            {
                *pos += 1;
                let name =
                    alias(t, pos).unwrap_or_else(|| path.last().cloned().unwrap_or_default());
                out.push((path, Bind::Name(name)));
                return;
            }
            Some(Tok::Ident(s)) => {
                path.push(s.clone());
                *pos += 1;
                if t.get(*pos) == Some(&Tok::Path) {
                    *pos += 1;
                    continue;
                }
                let name = alias(t, pos).unwrap_or_else(|| s.clone());
                out.push((path, Bind::Name(name)));
                break;
            }
            Some(Tok::Punct('*')) => {
                *pos += 1;
                out.push((path, Bind::Glob));
                break;
            }
            Some(Tok::Punct('{')) => {
                *pos += 1;
                while !matches!(t.get(*pos), None | Some(Tok::Punct('}'))) {
                    let before = *pos;
                    use_tree(t, pos, path.clone(), true, out);
                    if t.get(*pos) == Some(&Tok::Punct(',')) {
                        *pos += 1;
                    }
                    if *pos == before {
                        *pos += 1;
                    }
                }
                *pos += 1;
                break;
            }
            _ => break,
        }
    }
    if !braced {
        while !matches!(t.get(*pos), None | Some(Tok::Punct(';'))) {
            *pos += 1;
        }
    }
}

/// `as name` at `pos`, consumed.
fn alias(t: &[Tok], pos: &mut usize) -> Option<String> {
    match (t.get(*pos), t.get(*pos + 1)) {
        (Some(Tok::Ident(a)), Some(Tok::Ident(name))) if a == "as" => {
            *pos += 2;
            Some(name.clone())
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn leaves(src: &str) -> Vec<(String, Bind)> {
        parse(src)
            .uses
            .into_iter()
            .map(|u| (u.path.join("::"), u.bind))
            .collect()
    }

    #[test]
    fn nested_use_trees_are_flattened_with_their_bindings() {
        let got = leaves("pub(crate) use crate::{a::{b, c as d}, e::*, f::{self as g}};");
        assert!(parse("pub(in crate::x) use a::b; pub use c::d;")
            .uses
            .iter()
            .all(|u| u.export));
        assert!(!parse("#[cfg(test)] use a::b;").uses[0].export);
        let name = |s: &str| Bind::Name(s.into());
        assert_eq!(
            got,
            vec![
                ("crate::a::b".into(), name("b")),
                ("crate::a::c".into(), name("d")),
                ("crate::e".into(), Bind::Glob),
                ("crate::f".into(), name("g")),
            ]
        );
    }

    #[test]
    fn modules_items_and_code_paths_are_placed_in_their_scopes() {
        let p = parse(
            "#[cfg(test)]\n#[path = \"x_tests.rs\"]\nmod x;\nstruct S;\n\
             impl S { fn hidden() {} }\n\
             #[macro_export] macro_rules! shout { () => { $crate::diag::say() } }\n\
             mod inner { use super::S; fn f() { crate::a::b(); ::std::mem::drop(1); } }\n",
        );
        assert_eq!(p.mods.len(), 1);
        assert_eq!(p.mods[0].path_attr.as_deref(), Some("x_tests.rs"));
        assert_eq!(p.scopes[0].defs, vec!["S".to_string()]);
        assert_eq!(p.exported_macros, vec!["shout".to_string()]);
        assert_eq!(p.scopes[1].name, "inner");
        assert_eq!(p.scopes[1].defs, vec!["f".to_string()]);
        assert_eq!(p.uses[0].scope, 1);
        let paths: Vec<_> = p
            .paths
            .iter()
            .map(|c| (c.scope, c.segs.join("::")))
            .collect();
        assert_eq!(
            paths,
            vec![(0, "crate::diag::say".into()), (1, "crate::a::b".into())]
        );
    }
}
