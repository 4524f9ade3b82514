//! One crate's module tree, built by following `mod` declarations from its root file, and its
//! imports resolved to the files that define what they name.
//!
//! A name is followed through re-exports (`pub use`, and a parent's private `use` that a
//! child reaches with `super::`) to the file that defines it, so `use crate::World` imports
//! `world.rs`, not `lib.rs`. Importing a module itself (`use crate::grid;`) is no edge: the
//! paths written through it (`grid::Cell`) are. A re-export (`pub use`) is no edge either:
//! the module does not use what it publishes, its importers do, and their edges go to the
//! defining file. A file's use of what its own enclosing modules define (`super::Error` in
//! `state.rs` beside the `mod.rs` that declares it) is containment, not an import: the child
//! is a part of its parent, which holds the types its parts share.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::parse::{parse, Bind, Parsed};

/// One module of the crate.
struct Module {
    /// Index of its file in [`Crate::files`].
    file: usize,
    /// Its scope in that file (0, or an inline module).
    scope: usize,
    parent: Option<usize>,
    children: BTreeMap<String, usize>,
    /// Its path from the crate root (`[]` for the root).
    path: Vec<String>,
}

/// A file of the crate, read.
pub struct File {
    /// Its path, relative to the workspace.
    pub path: PathBuf,
    parsed: Parsed,
    /// Compiled for tests only: declared under `#[cfg(test)]`, or inside such a file.
    test: bool,
    /// The module of each of its scopes.
    modules: Vec<usize>,
}

/// One crate (a library, binary, test or example target): its files and modules.
pub struct Crate {
    /// Every file of the crate, the root first.
    pub files: Vec<File>,
    modules: Vec<Module>,
    /// `#[macro_export]` macros, which live at the crate root: name -> file.
    macros: BTreeMap<String, usize>,
}

/// An import of one file by another, and the name taken.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct Edge {
    /// The importing file.
    pub from: PathBuf,
    /// The file that defines what is imported.
    pub to: PathBuf,
    /// The imported name (the first segment that names an item of `to`).
    pub name: String,
}

enum Target {
    Module(usize),
    Item(usize, String),
    Outside,
}

const FUEL: u32 = 24;

impl Crate {
    /// Reads the crate whose root file is `root` (`ws`-relative), following every `mod`.
    pub fn read(ws: &Path, root: &Path) -> Result<Crate, String> {
        let mut c = Crate {
            files: Vec::new(),
            modules: Vec::new(),
            macros: BTreeMap::new(),
        };
        c.add_file(ws, root.to_path_buf(), None, String::new(), false)?;
        Ok(c)
    }

    fn add_file(
        &mut self,
        ws: &Path,
        path: PathBuf,
        parent: Option<usize>,
        name: String,
        test: bool,
    ) -> Result<(), String> {
        let src = std::fs::read_to_string(ws.join(&path))
            .map_err(|e| format!("{}: {e}", path.display()))?;
        let parsed = parse(&src);
        let f = self.files.len();
        for m in &parsed.exported_macros {
            self.macros.insert(m.clone(), f);
        }
        let mut modules = Vec::new();
        for (s, scope) in parsed.scopes.iter().enumerate() {
            let (up, name) = if s == 0 {
                (parent, name.clone())
            } else {
                (Some(modules[scope.parent]), scope.name.clone())
            };
            modules.push(self.add_module(f, s, up, name));
        }
        let decls: Vec<_> = parsed
            .mods
            .iter()
            .map(|d| (d.scope, d.name.clone(), d.path_attr.clone(), test || d.test))
            .collect();
        let inline_dirs: Vec<PathBuf> = (0..parsed.scopes.len())
            .map(|s| inline_dir(&parsed, s))
            .collect();
        self.files.push(File {
            path: path.clone(),
            parsed,
            test,
            modules: modules.clone(),
        });
        let own_dir = children_dir(&path, parent.is_none());
        for (scope, name, attr, child_test) in decls {
            let child = match attr {
                Some(a) if scope == 0 => path.parent().unwrap_or(Path::new("")).join(a),
                Some(a) => own_dir.join(&inline_dirs[scope]).join(a),
                None => {
                    let dir = own_dir.join(&inline_dirs[scope]);
                    let flat = dir.join(format!("{name}.rs"));
                    if ws.join(&flat).exists() {
                        flat
                    } else {
                        dir.join(&name).join("mod.rs")
                    }
                }
            };
            if !ws.join(&child).exists() {
                return Err(format!(
                    "{}: `mod {name};` has no file ({})",
                    path.display(),
                    child.display()
                ));
            }
            self.add_file(ws, child, Some(modules[scope]), name, child_test)?;
        }
        Ok(())
    }

    fn add_module(
        &mut self,
        file: usize,
        scope: usize,
        parent: Option<usize>,
        name: String,
    ) -> usize {
        let id = self.modules.len();
        let mut path = parent
            .map(|p| self.modules[p].path.clone())
            .unwrap_or_default();
        if let Some(p) = parent {
            path.push(name.clone());
            self.modules[p].children.insert(name, id);
        }
        self.modules.push(Module {
            file,
            scope,
            parent,
            children: BTreeMap::new(),
            path,
        });
        id
    }

    /// The module path of a file from the crate root (`[]` for the root file).
    pub fn module_path(&self, file: usize) -> &[String] {
        &self.modules[self.files[file].modules[0]].path
    }

    /// Every import of one file of the crate by another.
    /// Test code is left out (see the [house rules](super)).
    pub fn edges(&self) -> Vec<Edge> {
        let mut out = Vec::new();
        for (f, file) in self.files.iter().enumerate().filter(|(_, file)| !file.test) {
            let ancestors = self.ancestor_files(f);
            let mut add = |t: Target| {
                if let Target::Item(to, name) = t {
                    if to != f && !ancestors.contains(&to) {
                        out.push(Edge {
                            from: file.path.clone(),
                            to: self.files[to].path.clone(),
                            name,
                        });
                    }
                }
            };
            for u in file.parsed.uses.iter().filter(|u| !u.export && !u.test) {
                let m = file.modules[u.scope];
                match (&u.bind, self.resolve(m, &u.path, FUEL)) {
                    (Bind::Glob, Target::Module(g)) => {
                        add(Target::Item(self.modules[g].file, "*".into()))
                    }
                    (_, t) => add(t),
                }
            }
            for p in file
                .parsed
                .paths
                .iter()
                .filter(|p| !file.parsed.scopes[p.scope].test)
            {
                add(self.resolve_local(file.modules[p.scope], &p.segs));
            }
        }
        out.sort();
        out.dedup();
        out
    }

    /// A path written in module `m`'s code: its first segment may also be a name bound by a
    /// `use` inside a function of `m`.
    fn resolve_local(&self, m: usize, segs: &[String]) -> Target {
        let module = &self.modules[m];
        let parsed = &self.files[module.file].parsed;
        let bound = parsed
            .uses
            .iter()
            .find(|u| !u.item && u.scope == module.scope && u.bind == Bind::Name(segs[0].clone()));
        match bound {
            Some(u) => {
                let mut full = u.path.clone();
                full.extend_from_slice(&segs[1..]);
                self.resolve(m, &full, FUEL)
            }
            None => self.resolve(m, segs, FUEL),
        }
    }

    /// The path `segs` as written in module `m`.
    fn resolve(&self, m: usize, segs: &[String], fuel: u32) -> Target {
        if fuel == 0 || segs.is_empty() {
            return Target::Outside;
        }
        let (mut at, mut rest) = match segs[0].as_str() {
            "crate" => (self.root(m), &segs[1..]),
            "self" => (m, &segs[1..]),
            "super" => {
                let mut at = m;
                let mut rest = segs;
                while rest.first().map(String::as_str) == Some("super") {
                    match self.modules[at].parent {
                        Some(p) => at = p,
                        None => return Target::Outside,
                    }
                    rest = &rest[1..];
                }
                (at, rest)
            }
            _ => match self.lookup(m, &segs[0], fuel) {
                Target::Module(c) => (c, &segs[1..]),
                t => return t,
            },
        };
        while let Some(name) = rest.first() {
            match self.lookup(at, name, fuel) {
                Target::Module(c) => at = c,
                Target::Item(f, n) => return Target::Item(f, n),
                Target::Outside => return Target::Item(self.modules[at].file, name.clone()),
            }
            rest = &rest[1..];
        }
        Target::Module(at)
    }

    /// What `name` is in module `m`: a child module, a `use` binding, an item it defines, a
    /// crate-root macro, or a name one of its glob imports brings.
    fn lookup(&self, m: usize, name: &str, fuel: u32) -> Target {
        let module = &self.modules[m];
        if let Some(&c) = module.children.get(name) {
            return Target::Module(c);
        }
        let parsed = &self.files[module.file].parsed;
        let item_uses = || {
            parsed
                .uses
                .iter()
                .filter(|u| u.item && u.scope == module.scope)
        };
        if let Some(u) = item_uses().find(|u| u.bind == Bind::Name(name.to_string())) {
            return self.resolve(m, &u.path, fuel - 1);
        }
        if parsed.scopes[module.scope].defs.iter().any(|d| d == name) {
            return Target::Item(module.file, name.to_string());
        }
        if module.parent.is_none() {
            if let Some(&f) = self.macros.get(name) {
                return Target::Item(f, name.to_string());
            }
        }
        for u in item_uses().filter(|u| u.bind == Bind::Glob) {
            if let Target::Module(g) = self.resolve(m, &u.path, fuel - 1) {
                if let t @ (Target::Item(..) | Target::Module(_)) = self.lookup(g, name, fuel - 1) {
                    return t;
                }
            }
        }
        Target::Outside
    }

    /// The files of the modules that contain file `f`'s module (its `mod.rs`, ..., the root).
    fn ancestor_files(&self, f: usize) -> Vec<usize> {
        let mut out = Vec::new();
        let mut m = self.modules[self.files[f].modules[0]].parent;
        while let Some(p) = m {
            out.push(self.modules[p].file);
            m = self.modules[p].parent;
        }
        out
    }

    fn root(&self, mut m: usize) -> usize {
        while let Some(p) = self.modules[m].parent {
            m = p;
        }
        m
    }
}

/// Where a file's child modules live: beside it for a crate root or `mod.rs`, else in the
/// directory named after it.
fn children_dir(path: &Path, root: bool) -> PathBuf {
    let dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
    match path.file_stem().and_then(|s| s.to_str()) {
        Some("mod") => dir,
        _ if root => dir,
        Some(stem) => dir.join(stem),
        None => dir,
    }
}

/// The directory of inline module `s` below its file's children directory (`a/b` for
/// `mod a { mod b { ... } }`).
fn inline_dir(p: &Parsed, mut s: usize) -> PathBuf {
    let mut names = Vec::new();
    while s != 0 {
        names.push(p.scopes[s].name.clone());
        s = p.scopes[s].parent;
    }
    names.iter().rev().collect()
}
