//! Rings of the file graph: its strongly connected components of more than one file (Tarjan).

use std::collections::BTreeMap;
use std::path::PathBuf;

use super::tree::Edge;

/// Files that import each other, directly or around a ring, and the imports between them.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Ring {
    /// The ring's files, sorted.
    pub files: Vec<PathBuf>,
    /// Every import between two of them: (from, to, names taken).
    pub imports: Vec<(PathBuf, PathBuf, Vec<String>)>,
}

/// Every ring of `edges`, sorted by their first file.
pub fn rings(edges: &[Edge]) -> Vec<Ring> {
    let mut ids: BTreeMap<&PathBuf, usize> = BTreeMap::new();
    for e in edges {
        for p in [&e.from, &e.to] {
            let n = ids.len();
            ids.entry(p).or_insert(n);
        }
    }
    let mut names = vec![PathBuf::new(); ids.len()];
    for (p, &i) in &ids {
        names[i] = (*p).clone();
    }
    let mut adj = vec![Vec::new(); ids.len()];
    for e in edges {
        adj[ids[&e.from]].push(ids[&e.to]);
    }
    let mut t = Tarjan {
        adj: &adj,
        index: vec![None; adj.len()],
        low: vec![0; adj.len()],
        on: vec![false; adj.len()],
        stack: Vec::new(),
        next: 0,
        out: Vec::new(),
    };
    for v in 0..adj.len() {
        if t.index[v].is_none() {
            t.visit(v);
        }
    }
    let mut rings: Vec<Ring> = t
        .out
        .into_iter()
        .filter(|c| c.len() > 1)
        .map(|c| {
            let mut files: Vec<PathBuf> = c.iter().map(|&i| names[i].clone()).collect();
            files.sort();
            let mut imports: BTreeMap<(PathBuf, PathBuf), Vec<String>> = BTreeMap::new();
            for e in edges
                .iter()
                .filter(|e| files.contains(&e.from) && files.contains(&e.to))
            {
                imports
                    .entry((e.from.clone(), e.to.clone()))
                    .or_default()
                    .push(e.name.clone());
            }
            let imports = imports
                .into_iter()
                .map(|((f, t), mut n)| {
                    n.sort();
                    n.dedup();
                    (f, t, n)
                })
                .collect();
            Ring { files, imports }
        })
        .collect();
    rings.sort_by(|a, b| a.files.cmp(&b.files));
    rings
}

struct Tarjan<'a> {
    adj: &'a [Vec<usize>],
    index: Vec<Option<usize>>,
    low: Vec<usize>,
    on: Vec<bool>,
    stack: Vec<usize>,
    next: usize,
    out: Vec<Vec<usize>>,
}

impl Tarjan<'_> {
    fn visit(&mut self, v: usize) {
        self.index[v] = Some(self.next);
        self.low[v] = self.next;
        self.next += 1;
        self.stack.push(v);
        self.on[v] = true;
        for &w in &self.adj[v] {
            match self.index[w] {
                None => {
                    self.visit(w);
                    self.low[v] = self.low[v].min(self.low[w]);
                }
                Some(iw) if self.on[w] => self.low[v] = self.low[v].min(iw),
                Some(_) => {}
            }
        }
        if Some(self.low[v]) == self.index[v] {
            let mut comp = Vec::new();
            while let Some(w) = self.stack.pop() {
                self.on[w] = false;
                comp.push(w);
                if w == v {
                    break;
                }
            }
            self.out.push(comp);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn e(from: &str, to: &str) -> Edge {
        Edge {
            from: from.into(),
            to: to.into(),
            name: format!("{to}_item"),
        }
    }

    #[test]
    fn a_ring_through_three_files_is_one_component_and_a_chain_none() {
        let edges = [
            e("a", "b"),
            e("b", "c"),
            e("c", "a"),
            e("c", "d"),
            e("d", "e"),
        ];
        let r = rings(&edges);
        assert_eq!(r.len(), 1);
        assert_eq!(r[0].files, vec![PathBuf::from("a"), "b".into(), "c".into()]);
        assert_eq!(r[0].imports.len(), 3, "c -> d leaves the ring");
        assert!(rings(&edges[3..]).is_empty());
    }
}
