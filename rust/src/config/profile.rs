//! What the wheels roll on: the rail's sampled irregularity and the wheels' treads.

/// What the wheels roll on, sampled on a uniform grid x0 + i·dx and linearly interpolated:
/// the rail's irregularity r(x) (m, positive = dip) and each wheel's own tread irregularity
/// as a function of the wheel's position x (m, positive = the wheel centre drops, as over a
/// dip; a wheel flat repeats once per wheel circumference).
#[derive(Debug, Clone, Default)]
pub struct Profile {
    pub x0: f64,
    pub dx: f64,
    pub values: Vec<f64>,
    /// Empty (round wheels), or one row per wheel of the run (vehicles in order, wheelsets
    /// front to rear) on the grid of `values`; an empty row is a round wheel.
    pub treads: Vec<Vec<f64>>,
}

impl Profile {
    pub fn flat() -> Self {
        Self {
            x0: 0.0,
            dx: 1.0,
            values: Vec::new(),
            treads: Vec::new(),
        }
    }

    /// The grid interval holding x and the weight of its right end.
    #[inline]
    fn locate(&self, x: f64) -> (usize, f64) {
        let s = (x - self.x0) / self.dx;
        let i = (s.floor() as isize).clamp(0, self.values.len() as isize - 2) as usize;
        (i, s - i as f64)
    }

    /// r(x) of the rail; an empty profile is a perfectly smooth rail.
    #[inline]
    pub fn at(&self, x: f64) -> f64 {
        if self.values.is_empty() {
            return 0.0;
        }
        let (i, w) = self.locate(x);
        self.values[i] * (1.0 - w) + self.values[i + 1] * w
    }

    /// The irregularity under wheel `wheel` at position x: the rail's plus the wheel's tread.
    #[inline]
    pub fn under(&self, wheel: usize, x: f64) -> f64 {
        match self.treads.get(wheel) {
            Some(t) if !t.is_empty() => {
                let (i, w) = self.locate(x);
                (self.values[i] + t[i]) * (1.0 - w) + (self.values[i + 1] + t[i + 1]) * w
            }
            _ => self.at(x),
        }
    }

    pub fn x_last(&self) -> f64 {
        self.x0 + self.dx * (self.values.len() as f64 - 1.0)
    }
}
