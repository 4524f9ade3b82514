//! Planning with the terrain-hazard model (seed 002, §3).

use std::sync::Arc;

use hnav_coordinator::planner::{
    check_path, AStar, BasicTheta, LazyTheta, Planner, PlannerConfig, PlannerKind,
};
use hnav_coordinator::terrain::{HazardMap, TerrainParams};
use hnav_coordinator::PlanError;
use hnav_runtime::grid::{Cell, CornerCutting, Endpoint, Grid, Terrain, TerrainKind};

/// A `w x h` field (1 m cells) with a smooth Gaussian hill of height `peak` metres and spread
/// `sigma` metres centred at `(cx, cy)`.
fn hill(w: u32, h: u32, (cx, cy): (f64, f64), peak: f64, sigma: f64) -> Vec<f32> {
    (0..h)
        .flat_map(|y| {
            (0..w).map(move |x| {
                let d2 = (f64::from(x) - cx).powi(2) + (f64::from(y) - cy).powi(2);
                (peak * (-d2 / (2.0 * sigma * sigma)).exp()) as f32
            })
        })
        .collect()
}

fn planners(cfg: &PlannerConfig) -> Vec<Box<dyn Planner + Send>> {
    PlannerKind::ALL
        .iter()
        .map(|k| k.build(cfg.clone()))
        .collect()
}

#[test]
fn hazard_aware_route_is_longer_but_safer_over_a_hill() {
    let (w, h) = (41, 31);
    let heights = hill(w, h, (20.0, 15.0), 2.0, 5.0);
    let params = TerrainParams {
        hazard_weight: 4.0,
        ..TerrainParams::default()
    };
    let hz = Arc::new(HazardMap::from_heights(w, h, &heights, &params).unwrap());
    // The hill is climbable everywhere (under 30° and 0.20 m), only hazardous.
    assert_eq!(hz.impassable_count(), 0);
    // Its flanks carry hazard (the flat top and the plain around it hardly any).
    let flank_r = hz.hazard(Cell::new(15, 15)).unwrap();
    assert!(flank_r > 0.15, "the hill must carry hazard, R = {flank_r}");
    let grid = Grid::new(w, h).unwrap();
    let (s, t) = (Cell::new(2, 15), Cell::new(38, 15));

    let flat_cfg = PlannerConfig::default();
    let safe_cfg = PlannerConfig::default().with_hazard(hz.clone());
    for (mut flat, mut safe) in planners(&flat_cfg).into_iter().zip(planners(&safe_cfg)) {
        let f = flat.plan(&grid, s, t).unwrap().unwrap();
        let p = safe.plan(&grid, s, t).unwrap().unwrap();
        let (cf, cp) = (
            hz.route_hazard(&f.cells).unwrap(),
            hz.route_hazard(&p.cells).unwrap(),
        );
        println!(
            "{:<10} flat: L {:.3} c {:.3} | hazard-aware: L {:.3} c {:.3}",
            flat.name(),
            f.length,
            cf,
            p.length,
            cp
        );
        assert!(p.length > f.length + 0.5, "{}: not longer", flat.name());
        assert!(cp < 0.8 * cf, "{}: not safer", flat.name());
        let rule = CornerCutting::Forbidden;
        assert_eq!(check_path(&grid, Some(&hz), rule, &p.cells, s, t), Ok(()));
    }
}

/// A field with a 40-degree ridge along x = 6..=14 (flat elsewhere), open at rows `gap`.
fn ridge(w: u32, h: u32, gap: &[u32]) -> Vec<f32> {
    let rise = 40f64.to_radians().tan();
    (0..h)
        .flat_map(|y| {
            let open = gap.contains(&y);
            (0..w).map(move |x| {
                let up = (4.0 - (f64::from(x) - 10.0).abs()).max(0.0);
                if open {
                    0.0
                } else {
                    (up * rise) as f32
                }
            })
        })
        .collect()
}

#[test]
fn impassable_terrain_is_avoided_and_cannot_be_an_endpoint() {
    let (w, h) = (20u32, 12u32);
    let params = TerrainParams::default();
    let hz = HazardMap::from_heights(w, h, &ridge(w, h, &[2, 3, 4]), &params).unwrap();
    // The flanks are over the slope limit; their foot and rim are steps over 0.20 m.
    assert!(hz.is_impassable(Cell::new(8, 9)));
    assert!(hz.is_impassable(Cell::new(6, 9)));
    assert!(!hz.is_impassable(Cell::new(5, 9)));
    let hz = Arc::new(hz);
    let grid = Grid::new(w, h).unwrap();
    let (s, t) = (Cell::new(1, 10), Cell::new(18, 10));
    let cfg = PlannerConfig::default().with_hazard(hz.clone());
    for mut p in planners(&cfg) {
        let path = p.plan(&grid, s, t).unwrap().unwrap();
        assert_eq!(
            check_path(
                &grid,
                Some(&hz),
                CornerCutting::Forbidden,
                &path.cells,
                s,
                t
            ),
            Ok(())
        );
        assert!(hz.route_hazard(&path.cells).unwrap().is_finite());
        // A goal on the flank is refused as bad input, not answered with "no path".
        assert_eq!(
            p.plan(&grid, s, Cell::new(8, 9)),
            Err(PlanError::Impassable {
                endpoint: Endpoint::Goal,
                cell: Cell::new(8, 9)
            })
        );
    }
    // Without the gap there is no way across.
    let hz = HazardMap::from_heights(w, h, &ridge(w, h, &[]), &params).unwrap();
    let cfg = PlannerConfig::default().with_hazard(Arc::new(hz));
    for mut p in planners(&cfg) {
        assert_eq!(p.plan(&grid, s, t), Ok(None), "{}", p.name());
    }
}

#[test]
fn zero_hazard_weight_plans_like_no_hazard() {
    let (w, h) = (30, 20);
    let heights = hill(w, h, (15.0, 10.0), 1.5, 4.0);
    let hz = HazardMap::from_heights(w, h, &heights, &TerrainParams::default())
        .unwrap()
        .with_weight(0.0)
        .unwrap();
    let grid = Grid::new(w, h).unwrap();
    let (s, t) = (Cell::new(1, 3), Cell::new(28, 17));
    let cfg = PlannerConfig::default().with_hazard(Arc::new(hz));
    let mut a = AStar::new(cfg.clone());
    let mut b = BasicTheta::new(cfg.clone());
    let mut l = LazyTheta::new(cfg);
    let mut a0 = AStar::default();
    let mut b0 = BasicTheta::default();
    let mut l0 = LazyTheta::default();
    let len = |p: &mut dyn Planner| p.plan(&grid, s, t).unwrap().unwrap().length;
    assert!((len(&mut a) - len(&mut a0)).abs() < 1e-9);
    assert!((len(&mut b) - len(&mut b0)).abs() < 1e-9);
    assert!((len(&mut l) - len(&mut l0)).abs() < 1e-9);
}

#[test]
fn grid_terrain_layer_feeds_the_hazard_map() {
    let (w, h) = (12, 8);
    let heights = hill(w, h, (6.0, 4.0), 0.8, 2.0);
    let mut grid = Grid::new(w, h).unwrap();
    grid.set_terrain(Some(
        Terrain::new(TerrainKind::Elevation, heights.clone()).unwrap(),
    ))
    .unwrap();
    let params = TerrainParams::default();
    let from_grid = HazardMap::from_grid(&grid, &params).unwrap();
    let direct = HazardMap::from_heights(w, h, &heights, &params).unwrap();
    assert_eq!(from_grid, direct);
    // A hazard map of another shape is refused.
    let cfg = PlannerConfig::default().with_hazard(Arc::new(direct));
    let small = Grid::new(5, 5).unwrap();
    assert!(matches!(
        LazyTheta::new(cfg).plan(&small, Cell::new(0, 0), Cell::new(1, 1)),
        Err(PlanError::ShapeMismatch { .. })
    ));
}
