//! The generators' randomness: SplitMix64, seeded, so a finding's seed regenerates its file.

/// A small deterministic generator, with how hostile its case is: a quarter of the cases are well
/// formed (so the loaders' success paths and the checks after them run too), the rest carry hostile
/// values at rates from one in a hundred to one in three.
pub struct Rng {
    state: u64,
    hostility: f64,
}

impl Rng {
    pub fn new(seed: u64) -> Self {
        let hostility = [0.0, 0.01, 0.05, 0.3][(seed % 4) as usize];
        Self { state: seed, hostility }
    }

    /// True when this draw should be a hostile one.
    pub fn hostile(&mut self) -> bool {
        self.hostility > 0.0 && self.chance(self.hostility)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in 0..n (n > 0).
    pub fn below(&mut self, n: u64) -> u64 {
        self.next_u64() % n.max(1)
    }

    /// True with probability `p`.
    pub fn chance(&mut self, p: f64) -> bool {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64 <= p
    }

    /// One of the items.
    pub fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len() as u64) as usize]
    }

    /// A count: mostly small, sometimes at the edges a loader must guard (0, 1, huge).
    pub fn count(&mut self, typical: u64) -> u64 {
        if !self.hostile() {
            return 1 + self.below(typical.max(1));
        }
        match self.below(4) {
            0 => 0,
            1 => 1,
            2 => *self.pick(&[255, 256, 65_535, 65_536, u64::from(u32::MAX), u64::from(u32::MAX) + 1, u64::MAX]),
            _ => self.below(typical + 1),
        }
    }

    /// A number as text: ordinary, or one a parser must refuse or survive.
    pub fn number(&mut self) -> String {
        if !self.hostile() {
            return format!("{:.4}", (self.next_u64() % 20_000) as f64 / 1000.0 - 10.0);
        }
        match self.below(4) {
            0 => (*self.pick(&["nan", "inf", "-inf", "1e39", "-1e39", "3.4e38", "1e-45", "1e17", "1e18"])).into(),
            1 => (*self.pick(&["", "1x", "1.2.3", "--1", "0x10", "1e", "+", "١"])).into(),
            2 => "0".into(),
            _ => format!("{:.4}", (self.next_u64() % 20_000) as f64 / 1000.0 - 10.0),
        }
    }

    /// An index as text, in or around `0..n`, negative, zero or huge.
    pub fn index(&mut self, n: u64) -> i64 {
        if !self.hostile() {
            return self.below(n.max(1)) as i64 + 1;
        }
        match self.below(4) {
            0 => -(self.below(n + 2) as i64) - 1,
            1 => 0,
            2 => *self.pick(&[i64::from(u32::MAX), i64::MAX, i64::MIN, -1, n as i64 + 1]),
            _ => self.below(n.max(1)) as i64 + 1,
        }
    }

    /// Byte-level damage after the structure is made: flips, cuts and splices.
    pub fn damage(&mut self, bytes: &mut Vec<u8>) {
        if bytes.is_empty() || !self.hostile() {
            return;
        }
        for _ in 0..=self.below(4) {
            let at = self.below(bytes.len() as u64) as usize;
            match self.below(4) {
                0 => bytes[at] ^= 1 << self.below(8),
                1 => bytes[at] = self.next_u64() as u8,
                2 => bytes.truncate(at),
                _ => {
                    let from = self.below(bytes.len() as u64) as usize;
                    let piece: Vec<u8> = bytes[from..].iter().take(16).copied().collect();
                    bytes.splice(at..at, piece);
                }
            }
            if bytes.is_empty() {
                return;
            }
        }
    }
}
