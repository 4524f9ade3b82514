//! The MovingAI cell characters.
//!
//! A [`crate::grid::Grid`] keeps the original character of every cell as a [`Tile`], so a map
//! written back with [`crate::grid::write_map`] is byte-identical to the file that was read.
//! Which tiles block movement follows the ARCHITECTURE page ("`.` and `G` passable, `@ O T W`
//! blocked, `S` passable terrain with a cost"); this is stricter than the MovingAI page for `W`
//! (water is "traversable but not passable from terrain"), which no HNAV robot can do anyway.

use std::fmt;

/// One cell's MovingAI character.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
#[repr(u8)]
pub enum Tile {
    /// `.` passable ground.
    #[default]
    Ground = b'.',
    /// `G` passable ground (older MovingAI maps).
    GroundG = b'G',
    /// `@` out of bounds, blocked.
    OutOfBounds = b'@',
    /// `O` out of bounds, blocked.
    OutOfBoundsO = b'O',
    /// `T` trees, blocked.
    Tree = b'T',
    /// `S` swamp: passable, with traversal cost [`Tile::SWAMP_COST`].
    Swamp = b'S',
    /// `W` water: blocked for HNAV robots.
    Water = b'W',
}

impl Tile {
    /// All tiles, passable ones first.
    pub const ALL: [Tile; 7] = [
        Tile::Ground,
        Tile::GroundG,
        Tile::Swamp,
        Tile::OutOfBounds,
        Tile::OutOfBoundsO,
        Tile::Tree,
        Tile::Water,
    ];

    /// Cost multiplier of a swamp cell relative to ground. MovingAI gives no number; HNAV
    /// picks 2 so that a planner with terrain cost prefers a detour of up to twice the length.
    pub const SWAMP_COST: f32 = 2.0;

    /// The tile for a MovingAI character, or `None` for an unknown character.
    pub fn from_char(c: char) -> Option<Tile> {
        Some(match c {
            '.' => Tile::Ground,
            'G' => Tile::GroundG,
            '@' => Tile::OutOfBounds,
            'O' => Tile::OutOfBoundsO,
            'T' => Tile::Tree,
            'S' => Tile::Swamp,
            'W' => Tile::Water,
            _ => return None,
        })
    }

    /// The MovingAI character of this tile.
    pub fn to_char(self) -> char {
        char::from(self as u8)
    }

    /// Whether a robot may stand on this tile.
    pub fn is_passable(self) -> bool {
        matches!(self, Tile::Ground | Tile::GroundG | Tile::Swamp)
    }

    /// Traversal cost multiplier (1 for ground, [`Tile::SWAMP_COST`] for swamp), or `None` if
    /// the tile is blocked.
    pub fn cost(self) -> Option<f32> {
        match self {
            Tile::Ground | Tile::GroundG => Some(1.0),
            Tile::Swamp => Some(Tile::SWAMP_COST),
            _ => None,
        }
    }
}

impl fmt::Display for Tile {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.to_char())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chars_round_trip() {
        for t in Tile::ALL {
            assert_eq!(Tile::from_char(t.to_char()), Some(t));
        }
        assert_eq!(Tile::from_char('x'), None);
        assert_eq!(Tile::from_char('\r'), None);
    }

    #[test]
    fn passability_follows_architecture() {
        let passable: String = Tile::ALL
            .iter()
            .filter(|t| t.is_passable())
            .map(|t| t.to_char())
            .collect();
        assert_eq!(passable, ".GS");
        assert_eq!(Tile::Swamp.cost(), Some(2.0));
        assert_eq!(Tile::Tree.cost(), None);
    }
}
