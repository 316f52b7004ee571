//! The recorder's summaries of a series (mean and maximum, quantiles) and its bounded-memory
//! tallies: solve times in a log-scale histogram, per-frame series of the effectors' errors, the
//! held hands' contacts.

use nalgebra::Vector3;

use crate::imitation::output::HandPlacement;

/// Mean and maximum of a series.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MeanMax {
    /// Mean.
    pub mean: f64,
    /// Maximum.
    pub max: f64,
    /// Number of samples.
    pub count: usize,
}

/// What one hand held as a support achieved ([`crate::imitation::poubel::hand_support`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct HeldHand {
    /// Contacts made: the hand reached its contact point and held it.
    pub contacts: usize,
    /// Robot time from the start of placing to the contact, per contact (s).
    pub time_to_place: Spread,
    /// Distance of the hand from its contact point while held (m), over the held frames.
    pub held_distance: MeanMax,
}

/// Minimum, median and maximum of a series.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Spread {
    /// Minimum.
    pub min: f64,
    /// Median.
    pub median: f64,
    /// 99th percentile.
    pub p99: f64,
    /// Maximum.
    pub max: f64,
    /// Number of samples.
    pub count: usize,
}

impl Spread {
    pub(super) fn of(values: &mut [f64]) -> Self {
        if values.is_empty() {
            return Self::default();
        }
        values.sort_by(f64::total_cmp);
        let at = |p: f64| values[((values.len() - 1) as f64 * p).round() as usize];
        Self {
            min: values[0],
            median: at(0.5),
            p99: at(0.99),
            max: values[values.len() - 1],
            count: values.len(),
        }
    }
}

/// Solve times (µs) in bounded memory: counts in bins 0.1 % wide on a log scale from
/// [`TimeHistogram::FIRST`] µs, exact minimum and maximum. Quantiles are the centre of their
/// bin, so within 0.05 % of the exact order statistic, however long the run.
#[derive(Debug, Clone, Default)]
pub(super) struct TimeHistogram {
    bins: Vec<u64>,
    count: usize,
    min: f64,
    max: f64,
}

impl TimeHistogram {
    /// Lower edge of the first bin (µs); smaller times count in it.
    pub(super) const FIRST: f64 = 0.01;
    /// Width of a bin: its upper edge over its lower edge.
    pub(super) const RATIO: f64 = 1.001;
    /// Bins up to 10^8 µs (100 s); longer times count in the last.
    pub(super) const BINS: usize = 23_040;

    pub(super) fn record(&mut self, micros: f64) {
        if !micros.is_finite() {
            return;
        }
        if self.bins.is_empty() {
            self.bins = vec![0; Self::BINS];
            (self.min, self.max) = (micros, micros);
        }
        let bin = ((micros / Self::FIRST).ln() / Self::RATIO.ln()).floor();
        self.bins[(bin.max(0.0) as usize).min(Self::BINS - 1)] += 1;
        self.min = self.min.min(micros);
        self.max = self.max.max(micros);
        self.count += 1;
    }

    /// The value of rank `round((count − 1) p)` (0-based), as [`Spread`] defines its quantiles.
    pub(super) fn quantile(&self, p: f64) -> f64 {
        let rank = ((self.count - 1) as f64 * p).round() as u64;
        let mut seen = 0;
        for (bin, &n) in self.bins.iter().enumerate() {
            seen += n;
            if seen > rank {
                let centre = Self::FIRST * Self::RATIO.powf(bin as f64 + 0.5);
                return centre.clamp(self.min, self.max);
            }
        }
        self.max
    }

    pub(super) fn spread(&self) -> Spread {
        if self.count == 0 {
            return Spread::default();
        }
        Spread {
            min: self.min,
            median: self.quantile(0.5),
            p99: self.quantile(0.99),
            max: self.max,
            count: self.count,
        }
    }
}

#[derive(Debug, Clone, Default)]
pub(super) struct Series {
    sum: f64,
    max: f64,
    count: usize,
}

impl Series {
    pub(super) fn push(&mut self, v: f64) {
        self.sum += v;
        self.max = self.max.max(v);
        self.count += 1;
    }

    pub(super) fn summary(&self) -> MeanMax {
        MeanMax {
            mean: if self.count > 0 {
                self.sum / self.count as f64
            } else {
                0.0
            },
            max: self.max,
            count: self.count,
        }
    }
}

/// One hand's support record: when its current placing started, its contacts and their times,
/// and its distance from the point while held.
#[derive(Debug, Clone, Default)]
pub(super) struct HeldHandTally {
    /// Whether the hand was ever placed.
    pub(super) placed: bool,
    /// Robot time the current placing started, until the contact is made.
    placing_since: Option<f64>,
    /// Whether the hand held its point in the previous frame.
    holding: bool,
    place_times: Vec<f64>,
    distance: Series,
}

impl HeldHandTally {
    /// Records one frame: the hand's placement (if any) and the hand (world frame, m) at `time`.
    pub(super) fn record(
        &mut self,
        placement: Option<HandPlacement>,
        hand: Vector3<f64>,
        time: f64,
    ) {
        let Some(placement) = placement else {
            (self.placing_since, self.holding) = (None, false);
            return;
        };
        self.placed = true;
        if placement.holding {
            if !self.holding {
                let start = self.placing_since.take().unwrap_or(time);
                self.place_times.push(time - start);
            }
            self.distance.push((hand - placement.point).norm());
        } else {
            self.placing_since.get_or_insert(time);
        }
        self.holding = placement.holding;
    }

    pub(super) fn summary(&self) -> HeldHand {
        HeldHand {
            contacts: self.place_times.len(),
            time_to_place: Spread::of(&mut self.place_times.clone()),
            held_distance: self.distance.summary(),
        }
    }
}
