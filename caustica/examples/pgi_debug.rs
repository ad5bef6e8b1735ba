//! debug (not committed): one PhotonGi frame's raw and filtered indirect light as PNGs
use caustica_core::scene::builtin::builtin;
use caustica_core::techniques::create;
fn main() {
    let name = std::env::args().nth(1).unwrap_or("rooms".into());
    let s = builtin(&name).unwrap();
    let mut b = caustica::open_backend("cpu").unwrap();
    let mut st = serde_json::json!({"photons_w": 1024, "photons_h": 1024});
    if let Ok(extra) = std::env::var("EXTRA") {
        let e: serde_json::Value = serde_json::from_str(&extra).unwrap();
        for (k, v) in e.as_object().unwrap() {
            st[k] = v.clone();
        }
    }
    let mut t = create("photon-gi", b.as_mut(), &s, &st).unwrap();
    let stats = t.frame(b.as_mut(), &mut |_| {}).unwrap();
    println!("{:?}", stats.pass_ms);
    for o in ["indirect_raw", "indirect"] {
        let img = t.read_output(b.as_mut(), o).unwrap();
        caustica::output::write_png(
            std::path::Path::new(&format!("/tmp/dbg-{name}-{o}.png")),
            &img,
            8.0,
        )
        .unwrap();
    }
    t.free(b.as_mut()).unwrap();
}
