//! Every declared kernel is really dispatched by every backend: two Sspm frames of `prism`
//! (glass with dispersion) with pruning off, one per caustic filter (density, bilateral),
//! one CausticMap frame (a 64x64 atlas), one AdaptiveCaustics frame and one PhotonGi frame
//! after its ball (an instance) moved, run every pass of the kernel list between them, and each
//! backend's own pass timings must name every kernel that launches work, at least once.
//! `prepare_scene` launches nothing on the GPU-style backends; that it did its job shows
//! in the traced kernels having run on the prepared scene (they fail without it).
//! A backend that silently skipped a kernel (or reported the CPU's answer without running
//! its own) would miss its name here; conformance's per-kernel checks then judge the
//! values.

use caustica_conformance::{backends, small_settings};
use caustica_core::kernels::KERNELS;
use caustica_core::scene::builtin::builtin;
use caustica_core::techniques::adaptive_caustics::AdaptiveCausticsSettings;
use caustica_core::techniques::caustic_map::CausticMapSettings;
use caustica_core::techniques::photon_gi::PhotonGiSettings;
use caustica_core::{AtlasSettings, FrameSettings, ScreenSettings, TraversalSettings};
use caustica_core::{GatherFilter, Sspm, SspmSettings};

#[test]
fn every_backend_dispatches_every_declared_kernel() {
    let mut scene = builtin("prism").expect("built-in scene");
    scene.camera.width = 64;
    scene.camera.height = 36;
    for (name, mut b) in backends() {
        let mut passes = Vec::new();
        for filter in [GatherFilter::Density, GatherFilter::Bilateral] {
            let settings = SspmSettings {
                frame: FrameSettings {
                    prune: false,
                    // the opt-in temporal blend and A-Trous iterations, with the bilateral
                    // filter
                    temporal: filter == GatherFilter::Bilateral,
                    atrous_iterations: if filter == GatherFilter::Bilateral {
                        2
                    } else {
                        0
                    },
                    ..small_settings(64).frame
                },
                screen: ScreenSettings {
                    filter,
                    ..small_settings(64).screen
                },
                // the density run deposits inside the trace, the bilateral one through
                // deposit_screen
                fused_deposit: filter == GatherFilter::Density,
                ..small_settings(64)
            };
            let mut s = Sspm::new(b.as_mut(), &scene, settings).expect("valid scene");
            let stats = s.frame(b.as_mut(), &mut |_| {}).expect("frame");
            s.free(b.as_mut()).expect("free");
            assert!(
                stats.photons_stored > 0,
                "{name}: traced kernels saw no scene"
            );
            passes.extend(stats.passes);
        }
        let settings = CausticMapSettings {
            frame: FrameSettings {
                photons_w: 64,
                photons_h: 64,
                prune: false,
                ..CausticMapSettings::default().frame
            },
            atlas: AtlasSettings {
                atlas_size: 64,
                ..CausticMapSettings::default().atlas
            },
            ..CausticMapSettings::default()
        };
        let mut t =
            caustica_core::techniques::caustic_map::CausticMap::new(b.as_mut(), &scene, settings)
                .expect("valid scene");
        let stats = t.frame(b.as_mut(), &mut |_| {}).expect("frame");
        t.free(b.as_mut()).expect("free");
        assert!(
            stats.photons_deposited > 0,
            "{name}: caustic map saw no photon"
        );
        passes.extend(stats.passes);
        // Wyman 2009's traversal: the adaptive trace and refine_clusters (the finest
        // level's slots judged, not deposited by its trace)
        let adaptive = AdaptiveCausticsSettings {
            traversal: TraversalSettings {
                start_grid: 16,
                fused_finest: false,
                ..AdaptiveCausticsSettings::default().traversal
            },
            ..caustica_conformance::adaptive_over(&CausticMapSettings {
                frame: FrameSettings {
                    photons_w: 64,
                    photons_h: 64,
                    ..CausticMapSettings::default().frame
                },
                atlas: AtlasSettings {
                    atlas_size: 64,
                    ..CausticMapSettings::default().atlas
                },
                ..CausticMapSettings::default()
            })
        };
        let mut t = caustica_core::techniques::adaptive_caustics::AdaptiveCaustics::new(
            b.as_mut(),
            &scene,
            adaptive,
        )
        .expect("valid scene");
        let stats = t.frame(b.as_mut(), &mut |_| {}).expect("frame");
        t.free(b.as_mut()).expect("free");
        assert!(
            stats.photons_deposited > 0,
            "{name}: the adaptive traversal deposited no photon"
        );
        passes.extend(stats.passes);
        // PhotonGi: the RSM, the warp, the roulette trace and the splat, on `sphere`, whose
        // ball's smooth normals need Eq. 20's correction (the prism's flat faces do not),
        // its paths in sorted waves (`sort_indirect_paths`)
        let gi = PhotonGiSettings {
            frame: FrameSettings {
                photons_w: 64,
                photons_h: 64,
                ..PhotonGiSettings::default().frame
            },
            rsm_size: 16,
            indirect_schedule: caustica_core::techniques::photon_gi::IndirectSchedule::SortedWaves,
            ..PhotonGiSettings::default()
        };
        // and its ball an instance, moved before the frame (`place_vertices`)
        let mut ball = builtin("sphere").expect("built-in scene");
        (ball.camera.width, ball.camera.height) = (64, 36);
        let caustica_core::scene::Shape::Sphere { center, .. } = &mut ball.objects[1].shape else {
            panic!("sphere's object 1 is its glass ball");
        };
        let home = std::mem::replace(center, glam::Vec3::ZERO);
        let at =
            |y: f32| caustica_core::scene::Transform::from_translation(home + glam::Vec3::Y * y);
        ball.objects[1].transform = Some(at(0.0));
        let mut t = caustica_core::techniques::photon_gi::PhotonGi::new(b.as_mut(), &ball, gi)
            .expect("valid scene");
        t.set_object_transforms(b.as_mut(), &[(1, at(0.05))])
            .expect("move");
        let stats = t.frame(b.as_mut(), &mut |_| {}).expect("frame");
        t.free(b.as_mut()).expect("free");
        assert!(
            stats.photons_deposited > 0,
            "{name}: photon-gi splatted no photon"
        );
        passes.extend(stats.passes);
        for k in KERNELS.iter().filter(|k| k.name != "prepare_scene") {
            let pass = passes.iter().find(|p| p.name == k.name);
            assert!(
                pass.is_some_and(|p| p.dispatches >= 1),
                "backend {name} did not dispatch kernel {} (passes: {:?})",
                k.name,
                passes.iter().map(|p| &p.name).collect::<Vec<_>>()
            );
        }
    }
}
