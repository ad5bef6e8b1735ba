//! Compare caustic estimates by error against run time: Sspm's density-adaptive filter,
//! its seed's bilateral filter, and (in every record) the unfiltered deposit, at a few
//! photon budgets, against the independent f64 light tracer and against Sspm's own
//! converged estimate; prints the table `caustica report` prints. Needs the `report` feature (default).
//!
//! `cargo run --release -p caustica --example compare_techniques -- [BACKEND] [SCENE] [MAX_SIDE]`

use caustica::reference::light_tracer::LightTracerSpec;
use caustica::reference::ReferenceSpec;
use caustica::report::{run, table, ReportPlan};
use caustica::scene::builtin::builtin;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let backend = args.first().cloned().unwrap_or_else(|| "cpu".into());
    let scene = builtin(args.get(1).map_or("sphere", |s| s.as_str())).ok_or("unknown scene")?;
    let max_side: u32 = args.get(2).map_or(Ok(512), |s| s.parse())?;
    let budgets: Vec<(u32, u32)> = [128, 256, 512, 1024, 2048]
        .into_iter()
        .filter(|&s| s <= max_side)
        .map(|s| (s, s))
        .collect();
    let plan = ReportPlan {
        scenes: vec![scene],
        techniques: vec!["sspm".into()],
        backends: vec![backend],
        budgets,
        frames: vec![1],
        filters: vec!["density".into(), "bilateral".into()],
        settings: serde_json::Map::new(),
        repeats: 2,
        reference: ReferenceSpec {
            width: 160,
            height: 90,
            photons_side: 512,
            target_noise: 0.03,
            max_frames: 64,
            ..ReferenceSpec::default()
        },
        // the independent reference: 8 batches of 2^20 photons (a few seconds on `sphere`)
        tracer: LightTracerSpec {
            photons: 1 << 20,
            batches: 8,
            ..LightTracerSpec::default()
        },
    };
    let cache = std::env::temp_dir().join("caustica-example-references");
    let records = run(&plan, &cache, &mut |line| eprintln!("{line}"))?;
    println!("{}", table(&records));
    Ok(())
}
