//! Meshes the L-shape with a field graded towards the re-entrant corner and prints the quality.
//!
//! `cargo run --release -p amber-meshgen --example graded_lshape -- 1.0`
use amber_meshgen::{FnSize, Mesh2dParams, PolygonDomain, QualityReport, generate_2d};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let scale: f64 = std::env::args().nth(1).map(|s| s.parse()).transpose()?.unwrap_or(1.0);
    let domain = PolygonDomain::lshape([0.5, 0.5])?;
    let field = FnSize(move |x: [f64; 2]| {
        scale * (0.003 + 0.3 * ((x[0] - 0.5).powi(2) + (x[1] - 0.5).powi(2)).sqrt()).min(0.1)
    });
    let start = std::time::Instant::now();
    let mesh = generate_2d(&domain, &field, &Mesh2dParams::default())?;
    let seconds = start.elapsed().as_secs_f64();
    let report = QualityReport::measure(&mesh, &field);
    println!("{report:?}\n{seconds:.3} s, {:.0} triangles/s", mesh.num_elements() as f64 / seconds);
    Ok(())
}
