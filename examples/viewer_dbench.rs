// TEMPORARY (not committed): display pass cost at 512².
use mislab::gpu::GpuContext;
use mislab::gpu_types::GpuAccum;
use mislab::viewer::display::*;
use std::time::Instant;
fn main() {
    let ctx = GpuContext::new().unwrap();
    let (w, h) = (512u32, 512u32);
    let acc = vec![GpuAccum { mean: [0.5, 0.2, 0.1], count: 4, m2: [0.1; 3], nonfinite: 0 }; (w * h) as usize];
    let a = ctx.storage_buffer("a", &acc, wgpu::BufferUsages::empty());
    let p = ctx.storage_buffer("p", &acc[..64 * 64], wgpu::BufferUsages::empty());
    let pass = DisplayPass::new(&ctx, w, h).unwrap();
    for (view, st) in [(View::Image, false), (View::Image, true)] {
        for _ in 0..6 {
            let params = DisplayParams { width: w, height: h, view: view.tag(), exposure_scale: 1.0, split_x: w, preview_scale: 8, preview_width: 64, preview_height: 64, log_min: -3.0, log_max: 0.0, row_offset: 0, row_count: h, ..Default::default() };
            let t = Instant::now();
            let mut enc = ctx.device.create_command_encoder(&Default::default());
            pass.encode(&mut enc, &params, &DisplayInputs { accum: [&a, &a], preview: [&p, &p], reference: None }, st, None);
            ctx.queue.submit([enc.finish()]);
            let _ = pass.read(&ctx, st).unwrap();
            eprintln!("{view:?} stats={st}: {:.1} ms", t.elapsed().as_secs_f64() * 1e3);
        }
    }
}
