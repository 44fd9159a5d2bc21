//! Many lines summed up: the envelope (min, RMS, max at each x) of many series sampled
//! at the same x, plus the few series that reach furthest from zero, so a plot of 24
//! links shows everything that happened without 24 tangled lines and a cut legend.

use super::Series;

/// At most this many series are drawn one line each; more are summed up.
pub const FEW: usize = 6;

/// Colour of the RMS line; its band (min to max) is a light shade of it.
const RMS: [u8; 3] = [0x40, 0x40, 0x40];
/// Width [px] of the lines of the worst series, thinner than the RMS line so it shows.
const WORST_WIDTH: u32 = 1;

/// `series` as they are if there are at most [`FEW`]; else one series of the RMS over
/// all of them at each x with a band from the smallest to the largest value (labelled
/// `RMS of 24 links, band min–max` with `noun` = `links`), followed by the
/// `worst` series of largest `max |y|`, largest first (ties: the earlier series), with
/// their own labels and the palette's colours, drawn 1 px wide.
///
/// The series are expected on one x grid (as a recorder's are): point `i` of the
/// envelope is at the x of the first series' point `i` and sums up point `i` of every
/// series that has one. Non-finite values are left out; where none is finite the
/// envelope has a gap.
pub fn summarize(series: &[Series], noun: &str, worst: usize) -> Vec<Series> {
    if series.len() <= FEW {
        return series.to_vec();
    }
    let n = series.len();
    let xs: Vec<f64> = series[0].points.iter().map(|p| p.0).collect();
    let (mut band, mut rms) = (Vec::new(), Vec::new());
    for (i, &x) in xs.iter().enumerate() {
        let values = series
            .iter()
            .filter_map(|s| s.points.get(i).map(|p| p.1))
            .filter(|v| v.is_finite());
        let (mut min, mut max, mut squares, mut count) =
            (f64::INFINITY, f64::NEG_INFINITY, 0.0, 0usize);
        for v in values {
            min = min.min(v);
            max = max.max(v);
            squares += v * v;
            count += 1;
        }
        if count == 0 {
            band.push((x, f64::NAN, f64::NAN));
            rms.push((x, f64::NAN));
        } else {
            band.push((x, min, max));
            rms.push((x, (squares / count as f64).sqrt()));
        }
    }
    let mut out = vec![Series::new(format!("RMS of {n} {noun}, band min–max"), rms)
        .with_band(band)
        .styled(RMS, 2)];
    out.extend(worst_of(series, worst).into_iter().map(|i| {
        let s = series[i].clone();
        Series {
            width: Some(s.width.unwrap_or(WORST_WIDTH)),
            ..s
        }
    }));
    out
}

/// Indices of the `k` series of largest `max |y|` (finite values only), largest first,
/// the earlier series first on a tie.
pub fn worst_of(series: &[Series], k: usize) -> Vec<usize> {
    let peak = |s: &Series| {
        s.points
            .iter()
            .map(|p| p.1.abs())
            .filter(|v| v.is_finite())
            .fold(f64::NEG_INFINITY, f64::max)
    };
    let mut order: Vec<(usize, f64)> = series.iter().map(peak).enumerate().collect();
    order.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    order.into_iter().take(k).map(|(i, _)| i).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn links(n: usize) -> Vec<Series> {
        (0..n)
            .map(|k| {
                let points = (0..5)
                    .map(|i| {
                        let t = i as f64;
                        // Link 13 (L14) spikes at t = 3, link 2 (L3) dips at t = 1.
                        let w = match (k, i) {
                            (13, 3) => 0.5,
                            (2, 1) => -0.4,
                            _ => 0.01 * k as f64 - 0.1,
                        };
                        (t, w)
                    })
                    .collect();
                Series::new(format!("L{}", k + 1), points)
            })
            .collect()
    }

    #[test]
    fn few_series_stay_as_they_are() {
        let s = links(6);
        assert_eq!(summarize(&s, "links", 4), s);
    }

    #[test]
    fn many_series_become_an_envelope_and_the_worst() {
        let s = links(24);
        let out = summarize(&s, "links", 4);
        let labels: Vec<&str> = out.iter().map(|s| s.label.as_str()).collect();
        assert_eq!(
            labels,
            ["RMS of 24 links, band min–max", "L14", "L3", "L24", "L23"]
        );
        assert_eq!(out[0].band[3].2, 0.5, "max");
        assert_eq!(out[0].band[1].1, -0.4, "min");
        assert_eq!(out[0].band[0].1, -0.1);
        let mean_sq: f64 = (0..24)
            .map(|k| (0.01 * k as f64 - 0.1).powi(2))
            .sum::<f64>()
            / 24.0;
        assert!((out[0].points[0].1 - mean_sq.sqrt()).abs() < 1e-15);
        assert_eq!(out[1].points, s[13].points);
        assert_eq!(out[1].width, Some(1));
    }

    #[test]
    fn gaps_and_ragged_series_do_not_panic() {
        let mut s = links(8);
        s[0].points.clear();
        for p in &mut s[1..] {
            p.points[2].1 = f64::NAN;
        }
        let out = summarize(&s, "links", 20);
        assert!(out[0].points.is_empty(), "x comes from the first series");
        assert_eq!(out.len(), 9);
        s.swap(0, 1);
        let out = summarize(&s, "links", 2);
        assert!(out[0].points[2].1.is_nan() && out[0].band[2].2.is_nan());
        assert_eq!(out.len(), 3);
    }
}
