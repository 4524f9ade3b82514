//! Property tests: random grids round-trip through the `.map` writer and reader, cell/id/index
//! conversions are inverse, and no input (random or mutated) makes a reader panic.

use std::path::Path;

use hnav_runtime::grid::{
    octile, octile_shortest_path, read_map, read_map_rows, read_scen, write_map, write_scen, Cell,
    CornerCutting, Direction, Grid, Tile,
};
use hnav_runtime::scenario::Scenario;
use proptest::prelude::*;

/// A random grid of 1..40 x 1..40 cells drawn from every MovingAI character, weighted to
/// mostly free cells so shortest-path properties have something to chew on.
fn grid_strategy() -> impl Strategy<Value = Grid> {
    // Indexed by a random byte 0..14: about half free, every character represented. Mapping
    // plain bytes is much faster than a per-cell `prop_oneof!` on 1600-cell grids.
    const TILES: [Tile; 14] = [
        Tile::Ground,
        Tile::Ground,
        Tile::Ground,
        Tile::Ground,
        Tile::Ground,
        Tile::GroundG,
        Tile::Swamp,
        Tile::OutOfBounds,
        Tile::OutOfBounds,
        Tile::OutOfBoundsO,
        Tile::Tree,
        Tile::Tree,
        Tile::Water,
        Tile::Ground,
    ];
    (1u32..40, 1u32..40).prop_flat_map(|(w, h)| {
        proptest::collection::vec(0..TILES.len(), (w * h) as usize).prop_map(move |ix| {
            let tiles = ix.into_iter().map(|i| TILES[i]).collect();
            Grid::from_tiles(w, h, tiles).expect("shape matches")
        })
    })
}

const SAMPLE_MAP: &str = "type octile\nheight 3\nwidth 4\nmap\n....\n.@T.\nG..S\n";
const SAMPLE_SCEN: &str = "version 1\n0\tm.map\t4\t3\t0\t0\t3\t2\t3.41421356\n";
const SAMPLE_SCENARIO: &str =
    "name = \"p\"\n[map]\nrows = [\"....\", \".@@.\"]\n[[agents]]\nstart = [0, 0]\ngoal = [3, 1]\nspeed = 1.0\n";

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, rng_seed: proptest::test_runner::RngSeed::Fixed(hnav_runtime::hash::test_seed(0x5ca1e)), ..ProptestConfig::default() })]

    #[test]
    fn map_write_read_round_trip(grid in grid_strategy()) {
        let text = write_map(&grid);
        let back = read_map(&text, "<prop>").unwrap();
        prop_assert_eq!(&back, &grid);
        prop_assert_eq!(write_map(&back), text.clone());
        // CRLF reads the same.
        prop_assert_eq!(read_map(&text.replace('\n', "\r\n"), "<prop>").unwrap(), grid);
    }

    #[test]
    fn inline_rows_match_map_text(grid in grid_strategy()) {
        let rows: Vec<String> = (0..grid.height()).filter_map(|y| grid.row_string(y)).collect();
        let back = read_map_rows(rows.iter().enumerate().map(|(i, r)| (i + 1, r.as_str())), "<rows>").unwrap();
        prop_assert_eq!(back, grid);
    }

    #[test]
    fn cell_id_and_index_are_inverse(w in 1u32..300, h in 1u32..300, x in 0u32..300, y in 0u32..300) {
        let grid = Grid::new(w, h).unwrap();
        let cell = Cell::new(x, y);
        if grid.contains(cell) {
            let id = grid.cell_id(cell);
            prop_assert!(id >= 1 && id <= w * h);
            prop_assert_eq!(id, y * w + x + 1);
            prop_assert_eq!(grid.cell_from_id(id), Some(cell));
            let index = grid.index(cell);
            prop_assert_eq!(index + 1, id as usize);
            prop_assert_eq!(grid.cell_at(index), Some(cell));
            prop_assert_eq!(grid.checked_index(cell), Some(index));
        } else {
            prop_assert_eq!(grid.checked_cell_id(cell), None);
            prop_assert_eq!(grid.checked_index(cell), None);
            prop_assert!(grid.is_blocked(cell));
        }
        let last = w * h;
        prop_assert_eq!(grid.cell_from_id(last + 1), None);
        prop_assert_eq!(grid.cell_from_id(last), Some(Cell::new(w - 1, h - 1)));
    }

    #[test]
    fn shortest_paths_are_valid_and_bounded(grid in grid_strategy(), a in any::<(u32, u32)>(), b in any::<(u32, u32)>(), cut in any::<bool>()) {
        let start = Cell::new(a.0 % grid.width(), a.1 % grid.height());
        let goal = Cell::new(b.0 % grid.width(), b.1 % grid.height());
        let rule = if cut { CornerCutting::Allowed } else { CornerCutting::Forbidden };
        if let Some((len, path)) = octile_shortest_path(&grid, start, goal, rule) {
            prop_assert!(len + 1e-9 >= octile(start, goal), "never shorter than the straight line");
            prop_assert_eq!(path.first(), Some(&start));
            prop_assert_eq!(path.last(), Some(&goal));
            let mut sum = 0.0;
            for w in path.windows(2) {
                let d = Direction::between(w[0], w[1]);
                prop_assert!(d.is_some_and(|d| grid.can_move(w[0], d, rule)));
                sum += d.map_or(0.0, |d| d.cost());
            }
            prop_assert!((sum - len).abs() < 1e-9);
        }
    }

    #[test]
    fn readers_never_panic_on_arbitrary_text(text in "\\PC{0,300}") {
        let _ = read_map(&text, "<fuzz>");
        let _ = read_scen(&text, "<fuzz>");
        let _ = Scenario::from_str(&text, "<fuzz>", Path::new("."));
    }

    #[test]
    fn readers_never_panic_on_mutated_input(pos in any::<prop::sample::Index>(), byte in any::<u8>(), cut in any::<bool>()) {
        for sample in [SAMPLE_MAP, SAMPLE_SCEN, SAMPLE_SCENARIO] {
            let mut bytes = sample.as_bytes().to_vec();
            let i = pos.index(bytes.len());
            if cut { bytes.truncate(i) } else { bytes[i] = byte }
            let text = String::from_utf8_lossy(&bytes);
            let lines = text.lines().count();
            if let Err(e) = read_map(&text, "<m>") {
                prop_assert!(e.line().is_some_and(|l| l >= 1 && l <= lines + 1), "{}", e);
            }
            if let Err(e) = read_scen(&text, "<s>") {
                prop_assert!(e.line().is_some_and(|l| l >= 1 && l <= lines + 1), "{}", e);
            }
            if let Ok(s) = read_scen(&text, "<s>") {
                let _ = write_scen(&s);
            }
            let _ = Scenario::from_str(&text, "<t>", Path::new("."));
        }
    }
}
