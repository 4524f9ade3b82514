//! The shipped MovingAI files (`maps/` at the repository root): every map loads and writes
//! back byte for byte, every `.scen` entry fits its map, and every optimal length matches the
//! octile oracle with corner cutting forbidden.

use std::path::{Path, PathBuf};

use hnav_runtime::grid::check::check_map;
use hnav_runtime::grid::{
    octile_shortest_path_len, read_map, read_map_file, read_scen, read_scen_file, validate_scen,
    write_map, write_scen, CornerCutting, Grid, ScenFile,
};

fn maps_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../maps")
}

fn files_with_ext(ext: &str) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(maps_dir())
        .expect("maps/ exists at the repository root")
        .map(|e| e.expect("readable dir entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == ext))
        .collect();
    files.sort();
    files
}

/// The shipped scenario files with their maps and expected entry counts: MovingAI's two and
/// the warehouse's generated one (`hnav map scen`, see maps/README.md).
fn scen_pairs() -> Vec<(Grid, ScenFile, usize)> {
    [
        ("random-32-32-10", 461),
        ("random-32-32-20", 409),
        ("warehouse-10-20-10-2-1", 500),
    ]
    .into_iter()
    .map(|(name, count)| {
        let grid = read_map_file(maps_dir().join(format!("{name}.map"))).unwrap();
        let scen = read_scen_file(maps_dir().join(format!("{name}-random-1.scen"))).unwrap();
        (grid, scen, count)
    })
    .collect()
}

#[test]
fn all_scen_entries_load_and_validate() {
    for (grid, scen, count) in scen_pairs() {
        assert_eq!(scen.entries.len(), count, "{}", scen.source_name);
        let errors = validate_scen(&grid, &scen);
        assert!(errors.is_empty(), "{}: {errors:?}", scen.source_name);
        // Entries keep their file lines (header is line 1).
        assert_eq!(scen.entries[0].line, 2);
        assert_eq!(scen.entries[count - 1].line, count + 1);
    }
}

#[test]
fn first_entry_of_random_32_32_10_is_as_published() {
    let scen = read_scen_file(maps_dir().join("random-32-32-10-random-1.scen")).unwrap();
    let e = &scen.entries[0];
    assert_eq!(
        (e.bucket, e.map.as_str(), e.map_width, e.map_height),
        (3, "random-32-32-10.map", 32, 32)
    );
    assert_eq!(
        ((e.start.x, e.start.y), (e.goal.x, e.goal.y)),
        ((11, 6), (7, 18))
    );
    assert_eq!(e.optimal_length, 13.65685425);
}

#[test]
fn every_map_round_trips_byte_exactly() {
    let maps = files_with_ext("map");
    assert!(
        maps.len() >= 10,
        "expected the shipped maps, found {maps:?}"
    );
    for path in maps {
        let original = std::fs::read_to_string(&path).unwrap();
        let grid = read_map(&original, &path.display().to_string()).unwrap();
        assert_eq!(
            write_map(&grid),
            original.replace("\r\n", "\n"),
            "{}",
            path.display()
        );
        // Reading the written text gives the same grid again.
        assert_eq!(read_map(&write_map(&grid), "<written>").unwrap(), grid);
    }
}

#[test]
fn every_scen_round_trips_byte_exactly() {
    let scens = files_with_ext("scen");
    assert_eq!(scens.len(), 3, "{scens:?}");
    for path in scens {
        let original = std::fs::read_to_string(&path).unwrap();
        let scen = read_scen(&original, "x.scen").unwrap();
        assert_eq!(
            write_scen(&scen),
            original.replace("\r\n", "\n"),
            "{}",
            path.display()
        );
    }
}

#[test]
fn octile_oracle_matches_every_optimal_length() {
    let mut checked = 0;
    for (grid, scen, _) in scen_pairs() {
        for e in &scen.entries {
            let len = octile_shortest_path_len(&grid, e.start, e.goal, CornerCutting::Forbidden)
                .unwrap_or_else(|| panic!("{}:{}: unreachable", scen.source_name, e.line));
            assert!(
                (len - e.optimal_length).abs() <= 1e-6,
                "{}:{}: oracle {len} vs file {}",
                scen.source_name,
                e.line,
                e.optimal_length
            );
            checked += 1;
        }
    }
    assert_eq!(checked, 461 + 409 + 500);
}

#[test]
fn corner_cutting_would_break_the_optimal_lengths() {
    // Guards against an oracle that ignores the rule: with cutting allowed some lengths shrink.
    let shorter: usize = scen_pairs()
        .iter()
        .map(|(grid, scen, _)| {
            scen.entries
                .iter()
                .filter(|e| {
                    let cut =
                        octile_shortest_path_len(grid, e.start, e.goal, CornerCutting::Allowed)
                            .unwrap();
                    cut < e.optimal_length - 1e-6
                })
                .count()
        })
        .sum();
    assert!(shorter > 0);
}

#[test]
fn map_check_reports_ok_for_shipped_pairs() {
    for name in [
        "random-32-32-10",
        "random-32-32-20",
        "warehouse-10-20-10-2-1",
    ] {
        let map = maps_dir().join(format!("{name}.map"));
        let scen = maps_dir().join(format!("{name}-random-1.scen"));
        let c = check_map(&map, Some(&scen)).unwrap();
        assert!(c.is_ok(), "{}", c.render(10));
        assert!(c.warnings.is_empty(), "{:?}", c.warnings);
    }
    // The wrong map is caught.
    let c = check_map(
        &maps_dir().join("random-32-32-20.map"),
        Some(&maps_dir().join("random-32-32-10-random-1.scen")),
    )
    .unwrap();
    assert!(!c.is_ok());
    assert_eq!(c.warnings.len(), 1);
}

#[test]
fn the_warehouse_scen_is_what_its_command_generates() {
    // maps/README.md: `hnav map scen maps/warehouse-10-20-10-2-1.map --agents 500 --seed 1`.
    let grid = read_map_file(maps_dir().join("warehouse-10-20-10-2-1.map")).unwrap();
    let generated =
        hnav_runtime::grid::scen_gen::generate_scen(&grid, "warehouse-10-20-10-2-1.map", 500, 1)
            .unwrap();
    let shipped =
        std::fs::read_to_string(maps_dir().join("warehouse-10-20-10-2-1-random-1.scen")).unwrap();
    assert_eq!(write_scen(&generated), shipped);
}
