//! Where the calibrated odometry's pose error comes from, on the synthetic
//! Monte Carlo runs of `odocal experiment montecarlo`: for each online filter
//! the median over runs of the position RMSE of the odometry integrated with
//! the estimate after each step (as online), with the estimate before each
//! step, with the final estimate, with the true parameters, and from 10 s on;
//! the heading RMSE; the final radius errors; the step-to-step jitter of
//! R_R − R_L after 20 s; the heading error at 5 s; and how often the
//! Adaptive-PF has the lower online position RMSE.
//!
//! `cargo run --release --no-default-features --example pose_error_sources -- RUNS [KEY=VALUE,...]`
//! (keys: shrink, msw, msv, tau, change, dof, nmin, dsig, fa, win, np, nmax,
//! pp, alpha, smin, obs, kps; `CHANGING=1` adds the radii step at 55 s,
//! `TS=K` prints run K over time on stderr).

use odocal::calib::synth::SynthData;
use odocal::calib::synth::{draw_truth, generate, RadiusStep, SynthParams};
use odocal::calib::{build, run, steps, CalibParams, CalibStep, Estimate, Method};
use odocal::geom::{self, Pose2};
use odocal::robot::DiffDrive;

/// The odometry of the steps, each integrated with the parameters `f(k)`
/// (as the calibration runner does), from the identity.
fn integrate(st: &[CalibStep], f: &dyn Fn(usize) -> DiffDrive) -> Vec<(f64, Pose2)> {
    let mut pose = Pose2::identity();
    let mut out = vec![(st[0].t0, pose)];
    let mut covered = st[0].t0;
    for (k, s) in st.iter().enumerate() {
        let dt = s.t1 - s.t0.max(covered);
        if dt > 0.0 {
            pose *= f(k).increment(s.omega_right * dt, s.omega_left * dt);
            out.push((s.t1, pose));
            covered = s.t1;
        }
    }
    out
}

/// Position (m) and heading (rad) RMSE of `tr` against the truth, from
/// `from` (s) on, the truth taken in its own pose at the first stamp.
fn rmse(tr: &[(f64, Pose2)], d: &SynthData, from: f64) -> (f64, f64) {
    let o = d.reference.pose_at(tr[0].0).unwrap();
    let (mut a, mut b, mut m) = (0.0, 0.0, 0);
    for (t, p) in tr {
        if *t < from {
            continue;
        }
        if let Some(q) = d.reference.pose_at(*t) {
            let q = geom::between(&o, &q);
            a += (p.translation.vector - q.translation.vector).norm_squared();
            b += geom::wrap_angle(geom::heading(p) - geom::heading(&q)).powi(2);
            m += 1;
        }
    }
    ((a / m as f64).sqrt(), (b / m as f64).sqrt())
}

const NOMINAL: DiffDrive = DiffDrive {
    r_right: 0.32,
    r_left: 0.32,
    wheel_base: 0.65,
};

/// The calibration settings with the `KEY=VALUE,...` overrides applied.
fn settings(variant: &str) -> CalibParams {
    let mut base = CalibParams::default();
    for kv in variant.split(',').filter(|s| !s.is_empty()) {
        let (k, v) = kv.split_once('=').expect("KEY=VALUE");
        let x: f64 = v.parse().expect("a number");
        match k {
            "shrink" => base.noise.kernel_shrink = x,
            "msw" => base.noise.model_sigma_w = x,
            "msv" => base.noise.model_sigma_v = x,
            "tau" => base.adaptive.residual_tau = x,
            "change" => base.change.enabled = x > 0.0,
            "dof" => base.noise.robust_dof = x,
            "nmin" => base.adaptive.n_min = x as usize,
            "dsig" => base.adaptive.dispersion_sigmas = x,
            "fa" => base.change.false_alarm = x,
            "win" => base.change.window = x,
            "np" => base.particles = Some(x as usize),
            "nmax" => base.adaptive.n_max = x as usize,
            "pp" => base.adaptive.per_particle = x,
            "alpha" => base.adaptive.alpha = x,
            "smin" => base.adaptive.sigma_min = x,
            "obs" => base.noise.observability_turn_rate = x,
            "kps" => base.noise.kalman_param_sigma = x,
            _ => panic!("unknown key {k}"),
        }
    }
    base
}

/// Heading error (rad) of `tr` at its pose `i` against the truth.
fn heading_error(tr: &[(f64, Pose2)], i: usize, d: &SynthData) -> f64 {
    let o = d.reference.pose_at(tr[0].0).unwrap();
    let q = geom::between(&o, &d.reference.pose_at(tr[i].0).unwrap());
    geom::wrap_angle(geom::heading(&tr[i].1) - geom::heading(&q))
}

/// Prints one run over time on stderr: parameter errors, spread, count,
/// heading error.
fn print_series(m: Method, h: &[Estimate], cur: &[(f64, Pose2)], d: &SynthData) {
    let mut next = 0.0;
    for (i, e) in h.iter().enumerate() {
        if e.t >= next {
            next += if e.t < 10.0 { 0.5 } else { 5.0 };
            let tr = d.truth_at(e.t);
            eprintln!(
                "{} t={:6.2} dR={:7.3} dL={:7.3} dD={:7.2} mm sR={:6.3} mm N={} heading={:7.3} mrad",
                m.as_str(),
                e.t,
                1e3 * (e.r_right - tr.r_right),
                1e3 * (e.r_left - tr.r_left),
                1e3 * (e.wheel_base - tr.wheel_base),
                1e3 * e.std_r_right,
                e.particles,
                1e3 * heading_error(cur, i + 1, d)
            );
        }
    }
}

/// The figures of one run (columns of the printed table).
fn run_values(h: &[Estimate], st: &[CalibStep], d: &SynthData) -> [f64; 10] {
    let cur = integrate(st, &|k| h[k].drive());
    let prior = integrate(st, &|k| if k == 0 { NOMINAL } else { h[k - 1].drive() });
    let fin = integrate(st, &|_| h.last().unwrap().drive());
    let tru = integrate(st, &|k| d.truth_at(st[k].t1));
    let (a, th) = rmse(&cur, d, 0.0);
    let end = d.truth_at(1e9);
    let f = h.last().unwrap();
    // Step-to-step change of R_R − R_L after 20 s, RMS.
    let (mut js, mut jn) = (0.0, 0);
    for w in h.windows(2).filter(|w| w[0].t > 20.0) {
        let dd = (w[1].r_right - w[1].r_left) - (w[0].r_right - w[0].r_left);
        js += dd * dd;
        jn += 1;
    }
    let i5 = cur.partition_point(|x| x.0 < 5.0).min(cur.len() - 1);
    [
        a,
        rmse(&prior, d, 0.0).0,
        rmse(&fin, d, 0.0).0,
        rmse(&tru, d, 0.0).0,
        rmse(&cur, d, 10.0).0,
        th,
        1e3 * (f.r_right - end.r_right).abs(),
        1e3 * (f.r_left - end.r_left).abs(),
        1e6 * (js / jn.max(1) as f64).sqrt(),
        1e3 * heading_error(&cur, i5, d).abs(),
    ]
}

/// Median (mean of the middle two for an even count).
fn median(mut x: Vec<f64>) -> f64 {
    x.sort_by(f64::total_cmp);
    let k = x.len();
    if k % 2 == 1 {
        x[k / 2]
    } else {
        0.5 * (x[k / 2 - 1] + x[k / 2])
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let runs: usize = args.get(1).map_or(10, |s| s.parse().unwrap());
    let base = settings(args.get(2).map_or("", |s| s.as_str()));
    let mut sp = SynthParams::default();
    if std::env::var("CHANGING").is_ok() {
        sp.duration = 110.0;
        sp.radius_step = Some(RadiusStep {
            time: 55.0,
            right: 0.004,
            left: 0.002,
        });
    }
    let series: Option<usize> = std::env::var("TS").ok().and_then(|s| s.parse().ok());
    let methods = [Method::AdaptivePf, Method::Pf, Method::Dkf, Method::Akf];
    println!("method | RMSE x,y online (m) | estimate before the step | final estimate | true parameters | from 10 s | RMSE θ online (rad) | err R_R (mm) | err R_L (mm) | jitter of R_R − R_L (µm/step) | heading error at 5 s (mrad)");
    let mut online: Vec<Vec<f64>> = vec![];
    for m in methods {
        let mut cols: Vec<Vec<f64>> = vec![vec![]; 10];
        for k in 0..runs {
            let seed = 1 + k as u64;
            let data = generate(&sp, draw_truth(seed), seed);
            let st = steps(&data.obs, &data.wheels, &data.gyro, sp.gyro_sigma);
            let mut p = base.clone();
            p.method = m;
            p.seed = seed;
            let mut cal = build(&p, NOMINAL).unwrap();
            let h = run(cal.as_mut(), &st, NOMINAL).history;
            if series == Some(k) {
                print_series(m, &h, &integrate(&st, &|k| h[k].drive()), &data);
            }
            for (c, v) in cols.iter_mut().zip(run_values(&h, &st, &data)) {
                c.push(v);
            }
        }
        online.push(cols[0].clone());
        let mut s = m.as_str().to_string();
        for c in cols {
            s += &format!(" | {:.4}", median(c));
        }
        println!("{s}");
    }
    for (i, m) in methods.iter().enumerate().skip(1) {
        let w = online[0]
            .iter()
            .zip(&online[i])
            .filter(|(a, b)| a < b)
            .count();
        println!(
            "adaptive-pf has the lower online RMSE x,y than {} in {w} of {runs} runs",
            m.as_str()
        );
    }
}
