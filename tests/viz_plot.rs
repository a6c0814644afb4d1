//! PNG figures: valid files of the asked size, with the series, text and
//! legend actually drawn.

use crate::support::scratch;
use odocal::viz::plot::{
    bar_chart, line_chart, render_line_chart, render_trajectory_plot, trajectory_plot, BarChart,
    LineChart, PathSeries, Rgb, Series, TrajectoryPlot,
};
use std::path::Path;

/// Decodes a PNG file into RGB8 with the png crate (independent of the
/// encoder's in-memory buffer).
fn decode(path: &Path) -> Rgb {
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = dec.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    buf.truncate(info.buffer_size());
    Rgb {
        width: info.width,
        height: info.height,
        data: buf,
    }
}

fn count_color(img: &Rgb, c: [u8; 3]) -> usize {
    img.data.chunks_exact(3).filter(|p| *p == c).count()
}

/// Dark (text/axis) pixels in the columns `x0..x1`.
fn dark_in_columns(img: &Rgb, x0: u32, x1: u32) -> usize {
    let w = img.width as usize;
    img.data
        .chunks_exact(3)
        .enumerate()
        .filter(|(i, p)| {
            let x = (i % w) as u32;
            x >= x0 && x < x1 && p.iter().all(|&v| v < 80)
        })
        .count()
}

const TRUTH: [u8; 3] = [0, 0, 0];
const APF: [u8; 3] = [31, 119, 180];
const DKF: [u8; 3] = [214, 39, 40];

/// A radius history converging to truth with a step at 55 s (paper Fig. 6b).
fn radius_chart() -> LineChart {
    let t: Vec<f64> = (0..1200).map(|i| i as f64 * 0.1).collect();
    let truth = |t: f64| if t < 55.0 { 0.3200 } else { 0.3240 };
    let est = |t: f64, tau: f64, start: f64| {
        let (t0, from) = if t < 55.0 {
            (0.0, start)
        } else {
            (55.0, 0.3200)
        };
        truth(t) + (from - truth(t)) * (-(t - t0) / tau).exp()
    };
    let series = |name: &str, tau: f64, color| {
        Series::new(name, t.iter().map(|&x| [x, est(x, tau, 0.3100)]).collect()).color(color)
    };
    LineChart::new("Right wheel radius: estimate vs truth", "time (s)")
        .panel(
            "R_R (m)",
            vec![
                Series::new("truth", t.iter().map(|&x| [x, truth(x)]).collect())
                    .color(TRUTH)
                    .dashed(),
                series("Adaptive-PF", 4.0, APF),
                series("DKF", 15.0, DKF),
            ],
        )
        .panel(
            "particles N",
            vec![Series::new(
                "Adaptive-PF",
                t.iter()
                    .map(|&x| {
                        [
                            x,
                            if (55.0..65.0).contains(&x) {
                                3000.0
                            } else {
                                500.0
                            },
                        ]
                    })
                    .collect(),
            )],
        )
}

#[test]
fn line_chart_png_has_size_series_and_legend() {
    let dir = scratch("line_chart_png");
    let path = dir.join("radius.png");
    let chart = radius_chart();
    line_chart(&path, &chart).unwrap();
    let img = decode(&path);
    assert_eq!((img.width, img.height), chart.size);
    assert_eq!(img, render_line_chart(&chart).unwrap());
    // Both methods and the dashed truth are drawn in their colours.
    assert!(count_color(&img, APF) > 1000, "Adaptive-PF line missing");
    assert!(count_color(&img, DKF) > 500, "DKF line missing");
    assert!(count_color(&img, TRUTH) > 300, "truth/text missing");
    // The legend column (right of the plots) holds text.
    assert!(dark_in_columns(&img, img.width - 150, img.width) > 200);
    // Most of the canvas stays background: the figure is not a smear.
    let white = count_color(&img, [255, 255, 255]);
    assert!(white > img.data.len() / 3 / 2, "white {white}");
}

#[test]
fn line_chart_without_points_is_an_error() {
    let chart = LineChart::new("empty", "time (s)")
        .panel("y (m)", vec![Series::new("none", vec![[f64::NAN, 1.0]])]);
    assert!(render_line_chart(&chart).is_err());
}

#[test]
fn trajectory_png_draws_every_path() {
    let dir = scratch("trajectory_png");
    let path = dir.join("traj.png");
    // A 6 m square (reference) and a drifting raw odometry that bends left.
    let mut reference = Vec::new();
    for side in 0..4 {
        for k in 0..=60 {
            let s = k as f64 * 0.1;
            reference.push(match side {
                0 => [s, 0.0],
                1 => [6.0, s],
                2 => [6.0 - s, 6.0],
                _ => [0.0, 6.0 - s],
            });
        }
    }
    let rot = |p: &[f64; 2], a: f64| {
        let a = a * p[0].hypot(p[1]) / 8.0;
        [
            p[0] * a.cos() - p[1] * a.sin(),
            p[0] * a.sin() + p[1] * a.cos(),
        ]
    };
    let raw: Vec<[f64; 2]> = reference.iter().map(|p| rot(p, 0.15)).collect();
    let cal: Vec<[f64; 2]> = reference.iter().map(|p| rot(p, 0.01)).collect();
    let plot = TrajectoryPlot::new(
        "Square 6 m x 6 m: odometry vs reference",
        vec![
            PathSeries::new("reference", reference)
                .color(TRUTH)
                .dashed(),
            PathSeries::new("raw odometry", raw).color(DKF),
            PathSeries::new("calibrated (Adaptive-PF)", cal).color(APF),
        ],
    );
    trajectory_plot(&path, &plot).unwrap();
    let img = decode(&path);
    assert_eq!((img.width, img.height), plot.size);
    assert_eq!(img, render_trajectory_plot(&plot).unwrap());
    assert!(count_color(&img, DKF) > 800);
    assert!(count_color(&img, APF) > 800);
}

#[test]
fn bar_chart_png_and_shape_checks() {
    let dir = scratch("bar_png");
    let path = dir.join("bars.png");
    let methods: Vec<String> = ["multinomial", "stratified", "systematic", "residual"]
        .map(String::from)
        .to_vec();
    let triggers: Vec<String> = ["every step", "N_eff < N/2", "max weight"]
        .map(String::from)
        .to_vec();
    let err = vec![
        vec![1.9, 1.5, 1.4, 1.6],
        vec![1.2, 1.0, 0.9, 1.1],
        vec![1.4, 1.2, 1.1, 1.3],
    ];
    let ms = vec![
        vec![0.09, 0.07, 0.06, 0.08],
        vec![0.05, 0.04, 0.035, 0.045],
        vec![0.06, 0.05, 0.04, 0.05],
    ];
    let chart = BarChart::new(
        "Resampling methods and triggers",
        methods.clone(),
        triggers.clone(),
    )
    .panel("radius error (%)", err.clone(), Some(vec![vec![0.2; 4]; 3]))
    .panel("time per iteration (ms)", ms, None);
    bar_chart(&path, &chart).unwrap();
    let img = decode(&path);
    assert_eq!((img.width, img.height), chart.size);
    // Three group colours (Tableau blue, orange, green) are all drawn.
    for c in [[31, 119, 180], [255, 127, 14], [44, 160, 44]] {
        assert!(count_color(&img, c) > 2000, "group colour {c:?} missing");
    }
    // A ragged panel is refused.
    let bad = BarChart::new("bad", methods, triggers).panel("x", vec![vec![1.0]], None);
    assert!(bar_chart(&dir.join("bad.png"), &bad).is_err());
    assert!(!dir.join("bad.png").exists());
}
