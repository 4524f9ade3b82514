use hnav_agent::neural_map::*;
use hnav_runtime::grid::Grid;
fn main() {
    let ids = [4, 5, 6, 7, 8, 9, 10, 11, 12, 22, 24, 25, 26, 27, 28, 29, 32, 42, 43, 45, 46, 47, 48, 49, 55, 59, 62, 63, 65, 66, 67, 69, 72, 79, 82, 83, 84, 85, 86, 87, 88, 89];
    let mut g = Grid::new(10, 10).unwrap();
    for i in ids { let c = g.cell_from_id(i).unwrap(); g.set_blocked(c, true); }
    for act in [Activation::Tanh, Activation::Linear] {
        for den in [Denominator::LinkedOnly, Denominator::InGrid, Denominator::AllEight] {
            let o = NeuralMapOptions { activation: act, denominator: den, ..NeuralMapOptions::dissertation() };
            let mut m = ReferenceMap::new(&g, o).unwrap();
            let r = m.build(g.cell_from_id(56).unwrap(), StopRule::FullActivation).unwrap();
            let v = |i| m.values()[i as usize - 1];
            println!("{act:?} {den:?} sweeps {} E23 {:e} E33 {:e} E34 {:e} g33 {:e} g34 {:e}", r.sweeps, v(23), v(33), v(34), v(33)-v(23), (v(34)-v(23))*0.7071);
        }
    }
}
