//! debug: mean splat vs mean deposit images of a scene (PNG), not committed
use caustica_core::frame::image::Image;
use caustica_core::scene::builtin::builtin;
use caustica_core::techniques::create;
fn main() {
    let name = std::env::args().nth(1).unwrap_or("cornell".into());
    let mut s = builtin(&name).unwrap();
    let (w, h): (u32, u32) = (
        std::env::var("W")
            .map(|v| v.parse().unwrap())
            .unwrap_or(192),
        std::env::var("H")
            .map(|v| v.parse().unwrap())
            .unwrap_or(108),
    );
    (s.camera.width, s.camera.height) = (w, h);
    let mut b = caustica::open_backend("cpu").unwrap();
    for est in ["splat", "deposit"] {
        let mut st = serde_json::json!({"photons_w": 256, "photons_h": 256, "estimator": est, "temporal": false, "atrous_iterations": 0});
        if let Ok(extra) = std::env::var("EXTRA") {
            let e: serde_json::Value = serde_json::from_str(&extra).unwrap();
            for (k, v) in e.as_object().unwrap() {
                st[k] = v.clone();
            }
        }
        let mut t = create("photon-gi", b.as_mut(), &s, &st).unwrap();
        let mut sum = vec![[0.0f32; 4]; (w * h) as usize];
        let k = 16;
        for i in 0..k {
            t.set_seed(i + 1);
            t.frame(b.as_mut(), &mut |_| {}).unwrap();
            let img = t.read_output(b.as_mut(), "indirect_raw").unwrap();
            for (a, p) in sum.iter_mut().zip(&img.pixels) {
                for c in 0..3 {
                    a[c] += p[c] / k as f32;
                }
                a[3] = 1.0;
            }
        }
        let tot: f64 = sum.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum();
        // row sums to find where the difference is
        let mut blocks = [[0.0f64; 4]; 4];
        for (i, p) in sum.iter().enumerate() {
            let (x, y) = (i as u32 % w, i as u32 / w);
            blocks[(y * 4 / h) as usize][(x * 4 / w) as usize] += (p[0] + p[1] + p[2]) as f64;
        }
        println!("{est}: total {tot:.4}");
        for r in blocks {
            println!("   {:?}", r.map(|v| v.round()));
        }
        caustica::output::write_png(
            std::path::Path::new(&format!("/tmp/dbg-{name}-{est}.png")),
            &Image::new(w, h, sum),
            4.0,
        )
        .unwrap();
        t.free(b.as_mut()).unwrap();
    }
}
