use lembo_sim::{camera::View, datapath::Datapath, raster, scene::Scene};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene = if args.len() > 1 {
        Scene::load(std::path::Path::new(&args[1])).unwrap()
    } else {
        Scene::default_scene()
    };
    let view = View::new(&scene.camera, scene.viewport);
    let t = std::time::Instant::now();
    let f = raster::render_functional(&scene, &view, 0.5, Datapath::F32, true).unwrap();
    println!("{:?} {:?}", t.elapsed(), f.counts);
    println!("{:?}", f.probe);
    f.framebuffer.to_image().save("/tmp/smoke.png").unwrap();
}
