//! Exploration (not shipped): oracle vs best no-effect MAE for synthetic designs.
use talus::calibrate::metrics::metrics;
use talus::calibrate::model::evaluate;
use talus::calibrate::params::Candidate;
use talus::calibrate::synthetic::{
    case_3d, material_params_2d, material_params_3d, synthetic_2d, synthetic_3d, truth_2d, truth_3d, Hidden,
    Synthetic2d, Synthetic3d, TRUE_2D,
};
use talus::calibrate::Model;
use talus::lumped2d::Options2d;
use talus::sim::SimParams;

fn report(name: &str, spec: &Synthetic3d) {
    let model = synthetic_3d(spec, SimParams::default()).unwrap();
    let all: Vec<usize> = (0..model.runs().len()).collect();
    let t = evaluate(&model, &truth_3d(spec), &all, 20, 1, 0).unwrap();
    let mt = metrics(model.runs(), &t);
    let mut best = (f64::INFINITY, 0.0, 0.0);
    for cr in [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7] {
        for phi in [25.0, 32.0, 40.0, 50.0] {
            let c = Candidate {
                params: material_params_3d("default", [cr, spec.material[1], phi, phi - 6.0]),
                ..Default::default()
            };
            let s = evaluate(&model, &c, &all, 12, 1, 0).unwrap();
            let m = metrics(model.runs(), &s);
            if m.runout_mae_m < best.0 {
                best = (m.runout_mae_m, cr, phi);
            }
        }
    }
    println!(
        "{name:<12} runs {:>3} obs mean {:>6.1}  oracle mae {:>5.2} floor {:>5.2} | best no-effect mae {:>5.2} (cr {} phi {}) ratio {:.2}",
        all.len(), mt.observed_mean_m, mt.runout_mae_m, mt.scatter_floor_mae_m, best.0, best.1, best.2, mt.runout_mae_m / best.0
    );
}

fn report_2d(name: &str, spec: &Synthetic2d) {
    let model = synthetic_2d(spec, Options2d::default()).unwrap();
    let all: Vec<usize> = (0..model.runs().len()).collect();
    let t = evaluate(&model, &truth_2d(spec), &all, 20, 1, 0).unwrap();
    let mt = metrics(model.runs(), &t);
    let mut best = (f64::INFINITY, 0.0, 0.0, 0.0);
    for rn in [0.15, 0.25, 0.35, 0.45, 0.6] {
        for rt in [0.6, 0.7, 0.8, 0.9] {
            for phi in [20.0, 26.0, 32.0, 38.0, 45.0] {
                let c = Candidate {
                    params: material_params_2d("ground", [rn, TRUE_2D[1], rt, TRUE_2D[3], phi, TRUE_2D[5]]),
                    ..Default::default()
                };
                let s = evaluate(&model, &c, &all, 12, 1, 0).unwrap();
                let m = metrics(model.runs(), &s);
                if m.runout_mae_m < best.0 {
                    best = (m.runout_mae_m, rn, rt, phi);
                }
            }
        }
    }
    println!(
        "{name:<12} runs {:>3} obs mean {:>6.1}  oracle mae {:>5.2} floor {:>5.2} | best no-effect mae {:>5.2} (rn {} rt {} phi {}) ratio {:.2}",
        all.len(), mt.observed_mean_m, mt.runout_mae_m, mt.scatter_floor_mae_m, best.0, best.1, best.2, best.3, mt.runout_mae_m / best.0
    );
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.iter().any(|a| a == "2d") {
        let d = Synthetic2d {
            profile: vec![(40.0, 35.0), (30.0, 10.0), (1000.0, 0.0)],
            releases: vec![(4.0, 0.5), (12.0, 5.0), (20.0, 15.0)],
            ..Default::default()
        };
        report_2d("2d_control", &d);
        let designs = [
            ("s1", vec![(15.0, 60.0), (1000.0, 12.0)], vec![(1.0, 0.5), (20.0, 0.5), (20.0, 15.0), (30.0, 30.0)]),
            ("s2", vec![(1000.0, 25.0)], vec![(5.0, 0.5), (10.0, 10.0), (15.0, 30.0)]),
            ("s3", vec![(1000.0, 15.0)], vec![(5.0, 0.5), (10.0, 10.0), (15.0, 30.0)]),
            ("s4", vec![(20.0, 40.0), (1000.0, 5.0)], vec![(5.0, 0.5), (10.0, 10.0), (15.0, 30.0)]),
        ];
        for (n, prof, rel) in designs {
            let s = Synthetic2d { profile: prof, releases: rel, ..d.clone() };
            report_2d(&format!("{n}_control"), &s);
            report_2d(&format!("{n}_speed"), &Synthetic2d { hidden: Hidden::SpeedRestitution(9.144), ..s });
        }
        report_2d(
            "2d_zone",
            &Synthetic2d { hidden: Hidden::SoftZone(vec![[2.0, 0.0], [9.0, 0.0]], [0.1, 0.5, 55.0]), ..d.clone() },
        );
        report_2d(
            "2d_zone_apron",
            &Synthetic2d { hidden: Hidden::SoftZone(vec![[45.0, 0.0], [60.0, 0.0]], [0.1, 0.5, 55.0]), ..d.clone() },
        );
        return;
    }
    for name in ["speed", "size", "zone", "control_a", "control_b"] {
        if !args.is_empty() && !args.iter().any(|a| a == name) {
            continue;
        }
        let spec = case_3d(name, 1).unwrap();
        report(name, &spec);
        for shape in ["cube", "flat_box"] {
            let s2 = Synthetic3d { shape: shape.into(), ..spec.clone() };
            report(&format!("{name}/{shape}"), &s2);
        }
    }
}
