//! What `--stats` prints after a render.

use firemedium::render::{self, scene};

/// What `--stats` prints after a render: the scene, what the plugin built per medium and its fire light (or why
/// it was left out), the render's time, rays, error estimate and light samples, failed plugin calls and the peak
/// memory.
pub(super) fn stats(
    sc: &scene::Scene,
    st: &render::Stats,
    load_seconds: f64,
    threads: usize,
) -> String {
    let mut out = String::new();
    out += &format!("scene: {:.3} s to load and build, {} primitives, {} lights, {} media, {} bins over {}–{} nm\n", load_seconds, sc.bvh.prims.len(), sc.lights.len(), sc.media.len(), sc.bins.n(), sc.bins.grid.min_nm(), sc.bins.grid.max_nm());
    for m in &sc.media_reports {
        out += &format!(
            "medium \"{}\": plugin built {:.1} MB in {:.3} s ({} channels)\n",
            m.name,
            m.bytes as f64 / 1e6,
            m.seconds,
            m.channels
        );
        if let Some(lr) = m.light {
            let li = lr.info;
            let line = match li.line_block {
                1 => "its voxels".to_string(),
                b => format!("blocks of {b}³ voxels"),
            };
            let bins = if lr.line_channels < m.channels {
                format!(" in {} of its {} channels", lr.line_channels, m.channels)
            } else {
                String::new()
            };
            out += &format!(
                "  fire light: {} emitting voxels, {:.4e} W, {:.4e} lm, {:.1} MB in {:.3} s; its line through {line}{bins}\n",
                li.voxels,
                li.power_w,
                li.power_lm,
                li.bytes as f64 / 1e6,
                li.build_seconds
            );
        }
        if let Some(why) = &m.light_left_out {
            out += &format!("  fire light: left out ({why})\n");
        }
    }
    if let Some(g) = &sc.guide {
        let [lo, hi] = g.bounds();
        out += &format!(
            "fire guide: {:.0} % of the surfaces' directions aim at the scattering fire's box {:.3?}–{:.3?} (--fire-guide)\n",
            100.0 * g.prob(),
            lo.to_array(),
            hi.to_array()
        );
    }
    out += &format!(
        "render: {:.3} s on {} threads, {} camera rays, {:.0} camera rays/s, {} passes ({})\n",
        st.seconds,
        threads,
        st.camera_rays,
        st.camera_rays as f64 / st.seconds.max(1e-9),
        st.passes,
        st.stop.describe()
    );
    if let Some(e) = st.rel_rmse_estimate {
        out += &format!("  estimated relative RMSE {e:.4} (from two interleaved halves of each pixel's samples: docs/guide/rendering.md)\n");
    }
    if st.fire_light_samples > 0 {
        out += &format!(
            "  fire light: {} samples, {:.2} per camera ray\n",
            st.fire_light_samples,
            st.fire_light_samples as f64 / st.camera_rays.max(1) as f64
        );
    }
    if st.plugin_failures.0 > 0 {
        out += &format!(
            "  plugin calls that failed: {} (first: {})\n",
            st.plugin_failures.0,
            st.plugin_failures.1.as_deref().unwrap_or("no message")
        );
    }
    if let Some(bytes) = firemedium::budget::peak_rss() {
        out += &format!("peak memory: {:.1} MB\n", bytes as f64 / 1e6);
    }
    out
}
