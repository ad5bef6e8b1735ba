//! What a finer tessellation of a scene's spheres costs: per segment count and backend,
//! the triangles, the time to create the technique (tessellation, scene upload, BVH
//! build) and the median pass times of a few frames.
//!
//! `cargo run --release -p caustica --example ball_tessellation_cost -- SCENE WxH SIDE
//! SEGMENTS[,SEGMENTS...] BACKEND[,BACKEND...] FRAMES [TECHNIQUE]`
//!
//! (for example `sphere 960x540 1024 192,384,768 cpu,vulkan 3`). Times are host wall
//! times on the backend's device; the passes as the frame statistics time them.

use caustica::scene::Shape;
use caustica::techniques::create;
use std::collections::BTreeMap;
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize, d: &str| a.get(i).cloned().unwrap_or_else(|| d.to_string());
    let base = caustica::scene::builtin::builtin(&arg(0, "sphere")).ok_or("unknown scene")?;
    let (w, h) = arg(1, "960x540")
        .split_once('x')
        .and_then(|(w, h)| Some((w.parse::<u32>().ok()?, h.parse::<u32>().ok()?)))
        .ok_or("size WxH")?;
    let side: u32 = arg(2, "1024").parse()?;
    let segments: Vec<u32> = arg(3, "192,384,768")
        .split(',')
        .map(|s| s.parse())
        .collect::<Result<_, _>>()?;
    let backends = arg(4, "cpu");
    let frames: usize = arg(5, "3").parse::<usize>()?.max(1);
    let technique = arg(6, "sspm");
    let settings = serde_json::json!({"frame": {"photons_w": side, "photons_h": side}});
    for backend_name in backends.split(',') {
        let mut b = caustica::open_backend(backend_name)?;
        for &n in &segments {
            let mut scene = base.clone();
            scene.camera.width = w;
            scene.camera.height = h;
            let mut triangles = 0usize;
            for o in &mut scene.objects {
                if let Shape::Sphere { segments, .. } = &mut o.shape {
                    *segments = n;
                }
                triangles += caustica::scene::shapes::tessellate(&o.shape).indices.len();
            }
            let t0 = Instant::now();
            let mut t = create(&technique, b.as_mut(), &scene, &settings)?;
            let create_ms = t0.elapsed().as_secs_f64() * 1e3;
            let mut passes: BTreeMap<String, Vec<f64>> = BTreeMap::new();
            let mut frame_ms = Vec::new();
            // a warm-up frame, then the timed ones
            for k in 0..=frames {
                let st = t.frame(b.as_mut(), &mut |_| {})?;
                if k == 0 {
                    continue;
                }
                frame_ms.push(st.frame_ms);
                for p in st.passes {
                    passes.entry(p.name).or_default().push(p.ms);
                }
            }
            t.free(b.as_mut())?;
            let list = passes
                .into_iter()
                .map(|(k, v)| format!("{k} {:.2}", median(v)))
                .collect::<Vec<_>>()
                .join(", ");
            println!(
                "{backend_name} segments {n}: {triangles} triangles, create {create_ms:.1} ms, \
                 frame {:.1} ms (median of {frames}); passes (ms): {list}",
                median(frame_ms)
            );
        }
    }
    Ok(())
}
