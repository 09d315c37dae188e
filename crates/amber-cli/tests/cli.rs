//! End-to-end runs of the `amber` binary.

use std::process::Command;

fn amber() -> Command {
    Command::new(env!("CARGO_BIN_EXE_amber"))
}

#[test]
fn meshes_an_lshape_and_remeshes_from_the_result() {
    let dir = tempfile::tempdir().unwrap();
    let first = dir.path().join("first.vtu");
    let status =
        amber().args(["mesh", "lshape", "--corner", "0.3,0.6", "--size", "0.05", "-o"]).arg(&first).status().unwrap();
    assert!(status.success());
    let mesh = amber_mesh::read_mesh::<2>(&first).unwrap();
    assert!(mesh.num_elements() > 300);
    assert!((mesh.total_volume() - (1.0 - 0.7 * 0.4)).abs() < 1e-12);

    // The first mesh's element sizes as the field: the second mesh has about as many elements.
    let second = dir.path().join("second.msh");
    let status =
        amber().args(["mesh", "--corner", "0.3,0.6", "--size"]).arg(&first).arg("-o").arg(&second).status().unwrap();
    assert!(status.success());
    let (remeshed, data) = amber_mesh::read_mesh_with_data::<2>(&second).unwrap();
    let ratio = remeshed.num_elements() as f64 / mesh.num_elements() as f64;
    assert!((0.8..1.25).contains(&ratio), "{ratio}");
    // One physical group per side of the L-shape, over every boundary edge.
    let groups: std::collections::BTreeSet<i32> = data.facet_tags.values().copied().collect();
    assert_eq!(groups.len(), 6, "{groups:?}");
    let boundary_edges = amber_mesh::FacetAdjacency::new(&remeshed).unwrap().boundary_facets().count();
    assert_eq!(data.facet_tags.len(), boundary_edges);

    let picture = dir.path().join("mesh.png");
    assert!(amber().args(["mesh", "--size", "0.1", "-o"]).arg(&picture).status().unwrap().success());
    assert!(std::fs::metadata(&picture).unwrap().len() > 1000);

    // Second order for Abaqus: 6-node triangles over the same corners; medit has none.
    let quadratic = dir.path().join("quadratic.inp");
    let args = ["mesh", "--corner", "0.3,0.6", "--size", "0.05", "--order", "2", "-o"];
    assert!(amber().args(args).arg(&quadratic).status().unwrap().success());
    let (corners, data) = amber_mesh::read_mesh_with_data::<2>(&quadratic).unwrap();
    assert_eq!(corners, mesh);
    assert_eq!(data.linearised.get("triangle6"), Some(&mesh.num_elements()));
    let output = amber().args(args).arg(dir.path().join("quadratic.mesh")).output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success() && stderr.contains("second-order"), "{stderr}");
}

/// `--size` with a tet mesh whose `size` cell array asks for fine tets in the core of a cube:
/// the solid is meshed fine there, not at its skin's sizes carried inwards.
#[test]
fn meshes_a_solid_to_a_field_given_as_a_tet_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let cube = dir.path().join("cube.json");
    std::fs::write(
        &cube,
        r#"{"dimension": 3,
        "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [0, 0, 1], [1, 0, 1], [0, 1, 1], [1, 1, 1]],
        "elements": [[0, 1, 3, 7], [0, 1, 7, 5], [0, 2, 7, 3], [0, 2, 6, 7], [0, 4, 5, 7], [0, 4, 7, 6]]}"#,
    )
    .unwrap();
    let uniform = dir.path().join("uniform.vtu");
    assert!(amber().arg("mesh").arg(&cube).args(["--size", "0.15", "-o"]).arg(&uniform).status().unwrap().success());
    let uniform = amber_mesh::read_mesh::<3>(&uniform).unwrap();

    let from_centre = |p: [f64; 3]| p.iter().map(|x| (x - 0.5) * (x - 0.5)).sum::<f64>().sqrt();
    let h = |p: [f64; 3]| 0.04 + 0.16 * (from_centre(p) / 0.5).min(1.0);
    let field = dir.path().join("field.vtu");
    let sizes: Vec<f64> = uniform.midpoints().into_iter().map(h).collect();
    amber_mesh::write_mesh(&uniform, &field, &amber_mesh::MeshData::new().with_cell("size", sizes)).unwrap();
    let graded = dir.path().join("graded.msh");
    let output = amber().arg("mesh").arg(&cube).arg("--size").arg(&field).arg("-o").arg(&graded).output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success() && stderr.contains("tetrahedra") && stderr.contains("size ratio"), "{stderr}");
    assert!(!stderr.contains("warning"), "{stderr}");
    let (mesh, data) = amber_mesh::read_mesh_with_data::<3>(&graded).unwrap();
    assert!((mesh.total_volume() - 1.0).abs() < 1e-9, "volume {}", mesh.total_volume());
    let faces: std::collections::BTreeSet<i32> = data.facet_tags.values().copied().collect();
    assert_eq!(faces.len(), 6, "{faces:?}");
    let mut core: Vec<f64> = (0..mesh.num_elements())
        .filter(|&e| from_centre(mesh.midpoint(e)) < 0.2)
        .map(|e| mesh.size(e) / h(mesh.midpoint(e)))
        .collect();
    core.sort_by(f64::total_cmp);
    let median = core[core.len() / 2];
    assert!((0.7..1.4).contains(&median), "core tets at {median} of the field ({} of them)", core.len());

    // A field mesh beside the geometry (another part, other units) meshes, with a warning.
    let moved: Vec<[f64; 3]> = uniform.vertices().iter().map(|p| [p[0] + 5.0, p[1], p[2]]).collect();
    let moved = amber_mesh::Mesh3::new(moved, uniform.cells().to_vec()).unwrap();
    let beside = dir.path().join("beside.vtu");
    amber_mesh::write_mesh(&moved, &beside, &amber_mesh::MeshData::new()).unwrap();
    let output = amber().arg("mesh").arg(&cube).arg("--size").arg(&beside).arg("-o").arg(&graded).output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success() && stderr.contains("100 % of the mesh lies outside"), "{stderr}");

    // A field of triangles does not size a solid.
    let flat = dir.path().join("flat.vtu");
    assert!(amber().args(["mesh", "--size", "0.2", "-o"]).arg(&flat).status().unwrap().success());
    let output = amber().arg("mesh").arg(&cube).arg("--size").arg(&flat).arg("-o").arg(&graded).output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success() && stderr.contains("flat.vtu"), "{stderr}");
}

/// The names a geometry gives its faces (here an OBJ's groups) name the written mesh's boundary
/// groups: gmsh physical groups in `.msh`, node sets and surfaces in `.inp`; a mesh file as the
/// geometry also names the new mesh's element group.
#[test]
fn names_the_boundary_groups_as_the_geometry_names_its_faces() {
    let dir = tempfile::tempdir().unwrap();
    let cube = dir.path().join("cube.obj");
    std::fs::write(
        &cube,
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
         g bottom\nf 1 4 3 2\ng top\nf 5 6 7 8\ng side walls\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n",
    )
    .unwrap();
    let msh = dir.path().join("cube.msh");
    let output = amber().arg("mesh").arg(&cube).args(["--size", "0.3", "-o"]).arg(&msh).output().unwrap();
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let (_, data) = amber_mesh::read_mesh_with_data::<3>(&msh).unwrap();
    let names: Vec<&str> = data.facet_names.values().map(String::as_str).collect();
    assert_eq!(names, ["bottom", "top", "side walls"]);
    let inp = dir.path().join("cube.inp");
    assert!(amber().arg("mesh").arg(&cube).args(["--size", "0.3", "-o"]).arg(&inp).status().unwrap().success());
    let text = std::fs::read_to_string(&inp).unwrap();
    assert!(text.contains("*NSET, NSET=bottom\n") && text.contains("*SURFACE, TYPE=ELEMENT, NAME=\"side walls\"\n"));
    // `amber convert` carries the names from format to format.
    let converted = dir.path().join("converted.inp");
    assert!(amber().arg("convert").arg(&msh).arg(&converted).status().unwrap().success());
    let text = std::fs::read_to_string(&converted).unwrap();
    assert!(text.contains("*NSET, NSET=top\n"));
    // An Abaqus part as the geometry: its faces and its element set, which a deck's section
    // assignment names, carry over to the new mesh.
    let part = dir.path().join("bracket.inp");
    std::fs::write(&part, text.replace("ELSET=domain\n", "ELSET=BRACKET\n")).unwrap();
    let remeshed = dir.path().join("remeshed.inp");
    let output = amber().arg("mesh").arg(&part).args(["--size", "0.25", "-o"]).arg(&remeshed).output().unwrap();
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let text = std::fs::read_to_string(&remeshed).unwrap();
    assert!(text.contains(", ELSET=BRACKET\n") && text.contains("*NSET, NSET=\"side walls\"\n"), "{text}");
}

/// Several geometries in one command: each meshed to the output with `{stem}` replaced; one
/// that fails is named, the others are still written, and the command fails.
#[test]
fn meshes_several_geometries_in_one_command() {
    let dir = tempfile::tempdir().unwrap();
    let template = dir.path().join("{stem}.vtu");
    let output = amber().args(["mesh", "lshape", "square", "--size", "0.1", "-o"]).arg(&template).output().unwrap();
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let lshape = amber_mesh::read_mesh::<2>(dir.path().join("lshape.vtu")).unwrap();
    let square = amber_mesh::read_mesh::<2>(dir.path().join("square.vtu")).unwrap();
    assert!((lshape.total_volume() - 0.75).abs() < 1e-12 && (square.total_volume() - 1.0).abs() < 1e-12);

    let missing = dir.path().join("missing.stl");
    let args = ["mesh", "lshape", missing.to_str().unwrap(), "--size", "0.1", "-o"];
    let output = amber().args(args).arg(dir.path().join("again-{stem}.vtu")).output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        !output.status.success() && stderr.contains("1 of 2 geometries failed") && stderr.contains("missing.stl"),
        "{stderr}"
    );
    assert!(dir.path().join("again-lshape.vtu").exists());

    for (args, needle) in [
        (vec!["mesh", "lshape", "square", "--size", "0.1", "-o", "one.vtu"], "{stem}"),
        (vec!["mesh", "a/part.stl", "b/part.stl", "--size", "0.1", "-o", "{stem}.vtu"], "the stem `part`"),
    ] {
        let output = amber().args(&args).current_dir(dir.path()).output().unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(!output.status.success() && stderr.contains(needle), "{args:?}: {stderr}");
    }
}

#[test]
fn converts_between_formats_in_the_dimension_of_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("square.json");
    std::fs::write(
        &json,
        r#"{"dimension": 2, "vertices": [[0, 0], [1, 0], [1, 1], [0, 1]],
        "elements": [[0, 1, 2], [0, 2, 3]], "cell_data": {"size": [0.5, 0.25]}}"#,
    )
    .unwrap();
    let msh = dir.path().join("square.msh");
    assert!(amber().arg("convert").arg(&json).arg(&msh).arg("--binary").status().unwrap().success());
    assert!(std::fs::read(&msh).unwrap().windows(7).any(|w| w == b"4.1 1 8"), "binary .msh");
    let vtk = dir.path().join("square.vtk");
    let output = amber().arg("convert").arg(&msh).arg(&vtk).output().unwrap();
    assert!(output.status.success());
    let summary = String::from_utf8_lossy(&output.stderr);
    assert!(
        summary.contains("2 2D elements in `domain`")
            && summary.contains("4 tagged facets (named: 1 `boundary`)")
            && !summary.contains("dropped"),
        "boundary lines are facets: {summary}"
    );
    let (mesh, data) = amber_mesh::read_mesh_with_data::<2>(&vtk).unwrap();
    assert_eq!((mesh.num_elements(), data.cell["size"].clone()), (2, vec![0.5, 0.25]));

    let bad = dir.path().join("bad.vtu");
    std::fs::write(&bad, "<VTKFile type=\"UnstructuredGrid\"><UnstructuredGrid><Piece NumberOfPoints=\"x\"").unwrap();
    for (input, output) in [(&bad, &vtk), (&json, &dir.path().join("x.ply")), (&json, &dir.path().join("x.inp"))] {
        let mut command = amber();
        command.arg("convert").arg(input).arg(output);
        if output.ends_with("x.inp") {
            command.arg("--binary");
        }
        let result = command.output().unwrap();
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert!(!result.status.success() && !stderr.contains("panicked"), "{stderr}");
        let named = if input == &bad { "bad.vtu" } else { "x." };
        assert!(stderr.contains(named), "{stderr}");
    }
}

#[test]
fn bad_input_fails_with_a_message_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.vtu");
    for args in [
        vec!["mesh", "--size", "-1"],
        vec!["mesh", "--size", "nan"],
        vec!["mesh", "--size", "/nonexistent.vtu"],
        vec!["mesh", "--corner", "1.5,0.5", "--size", "0.1"],
    ] {
        let output = amber().args(&args).arg("-o").arg(&out).output().unwrap();
        assert!(!output.status.success(), "{args:?} succeeded");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(stderr.to_lowercase().contains("error") && !stderr.contains("panicked"), "{args:?}: {stderr}");
    }
    // A flag that acts on a model's rollout is refused with --size, not ignored.
    for flag in [&["--refine-face", "1,0.01"][..], &["--min-size", "0.05"], &["--elements", "500"], &["--list-faces"]] {
        let output = amber().args(["mesh", "lshape", "--size", "0.1"]).args(flag).arg("-o").arg(&out).output().unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(
            !output.status.success() && stderr.contains(&format!("{} needs --model", flag[0])),
            "{flag:?}: {stderr}"
        );
    }
    let output = amber().args(["mesh", "lshape", "--size", "0.1", "--list-faces"]).output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success() && !stderr.contains("panicked"), "{stderr}");
}

#[test]
fn trains_a_smoke_model_resumes_it_and_generates_with_it() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../datasets/poisson.json");
    let run = dir.path().join("run");
    let data = dir.path().join("data");
    let config = dir.path().join("config.json");
    std::fs::write(&config, r#"{"steps": 40, "checkpoint_interval": 5, "validation_interval": 0}"#).unwrap();
    let train = || {
        let mut command = amber();
        command
            .args(["train", "--profile", "smoke", "--difficulty", "easy", "--config"])
            .arg(&config)
            .arg("--out")
            .arg(&run)
            .arg("--data")
            .arg(&data)
            .arg("--manifest")
            .arg(&manifest)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped());
        command
    };
    // Kill the first run once it has checkpointed (or let it finish on a very fast machine).
    let mut first = train().spawn().unwrap();
    let checkpoint = run.join("checkpoints/step-00000010");
    while !checkpoint.exists() && first.try_wait().unwrap().is_none() {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    first.kill().ok();
    first.wait().unwrap();
    // What a write killed mid-way leaves (the dead process's temporary file) is swept on resume.
    let killed_write = run.join(format!(".training_state.json.{}-0.tmp", first.id()));
    std::fs::write(&killed_write, "").unwrap();
    // The same command resumes from the newest checkpoint and finishes.
    let output = train().output().unwrap();
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    assert!(run.join("model/model.safetensors").exists());
    assert!(!killed_write.exists(), "the killed write's temporary is removed");
    let log = std::fs::read_to_string(run.join("train.jsonl")).unwrap();
    let steps: Vec<u64> = log
        .lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .filter(|v| v["kind"] == "step")
        .map(|v| v["step"].as_u64().unwrap())
        .collect();
    assert_eq!(steps, (1..=40).collect::<Vec<_>>(), "every step logged once, across the kill");
    // Both sessions are recorded (one, had the first finished before the kill), the second from
    // the checkpoint it resumed; one commit ran both, and the card names it alone.
    let record: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("training_time.json")).unwrap()).unwrap();
    let sessions = record["sessions"].as_array().unwrap();
    assert!(matches!(sessions.len(), 1 | 2), "{record}");
    assert_eq!(sessions[0]["first_step"], 0);
    assert!(sessions.get(1).is_none_or(|s| s["first_step"].as_u64().unwrap() >= 10), "{record}");
    let card: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("model/card.json")).unwrap()).unwrap();
    assert_eq!(card["commit"], sessions[0]["commit"]);

    // The model meshes a problem's domain from its load alone, scored against the problem's expert.
    let problem_file = data.join("easy/val/000.json");
    let out = dir.path().join("generated");
    let final_mesh = dir.path().join("final.msh");
    let output = amber()
        .args(["mesh", "--steps", "2", "--model"])
        .arg(&run)
        .arg("--problem")
        .arg(&problem_file)
        .arg("--every-step")
        .arg(&out)
        .arg("-o")
        .arg(&final_mesh)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    for file in ["step1.vtu", "step2.vtu", "step1.png", "step2.png"] {
        assert!(out.join(file).exists(), "{file} missing");
    }
    assert!(stderr.contains("step 2:") && stderr.contains("normalised DCD"), "{stderr}");
    let mesh = amber_mesh::read_mesh::<2>(&final_mesh).unwrap();
    let problem = amber_tasks::poisson::read_problem(&problem_file).unwrap();
    assert!((mesh.total_volume() - problem.expert_mesh.total_volume()).abs() < 1e-9);

    // The budget knob: the final mesh has the requested element count within ±10 %, on a domain
    // the model has never seen (a square with a hole, the problem's load).
    let square = dir.path().join("holed.json");
    std::fs::write(
        &square,
        r#"{"outer": [[0,0],[1,0],[1,1],[0,1]], "holes": [[[0.4,0.4],[0.4,0.6],[0.6,0.6],[0.6,0.4]]]}"#,
    )
    .unwrap();
    let mesh_square = |knobs: &[&str]| {
        let mut command = amber();
        command.arg("mesh").arg(&square).args(["--steps", "2"]).args(knobs).arg("--model").arg(&run);
        command.arg("--problem").arg(&problem_file).arg("-o").arg(&final_mesh).output().unwrap()
    };
    for elements in [300usize, 1200] {
        let output = mesh_square(&["--elements", &elements.to_string()]);
        assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
        let mesh = amber_mesh::read_mesh::<2>(&final_mesh).unwrap();
        let ratio = mesh.num_elements() as f64 / elements as f64;
        assert!((0.9..=1.1).contains(&ratio), "{} elements for {elements}", mesh.num_elements());
        assert!((mesh.total_volume() - 0.96).abs() < 1e-9);
    }

    // The size range: a range of one size makes the model's field uniform; an empty range is an
    // error naming the flags.
    for (bounds, ok) in [(["0.05", "0.05"], true), (["0.05", "0.01"], false)] {
        let output = mesh_square(&["--min-size", bounds[0], "--max-size", bounds[1]]);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.success(), ok, "{bounds:?}: {stderr}");
        if !ok {
            assert!(stderr.contains("--min-size") && !stderr.contains("panicked"), "{stderr}");
            continue;
        }
        let mut sizes = amber_mesh::read_mesh::<2>(&final_mesh).unwrap().sizes();
        sizes.sort_by(f64::total_cmp);
        let (low, high) = (sizes[sizes.len() / 20], sizes[sizes.len() * 19 / 20]);
        assert!(low > 0.04 && high < 0.06, "5 % and 95 % of sizes {low}, {high} for a field of 0.05");
    }

    // A refinement box: its elements take the box's size, where the same mesh without it has
    // coarser ones, and the far corner is left as it was. A box of the wrong dimension, or not a
    // box, is an error naming the flag.
    let medians = |knobs: &[&str]| {
        let output = mesh_square(knobs);
        assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
        let mesh = amber_mesh::read_mesh::<2>(&final_mesh).unwrap();
        let median_where = |inside: &dyn Fn([f64; 2]) -> bool| {
            let mut h: Vec<f64> =
                mesh.midpoints().iter().zip(mesh.sizes()).filter(|(x, _)| inside(**x)).map(|(_, h)| h).collect();
            h.sort_by(f64::total_cmp);
            h[h.len() / 2]
        };
        [median_where(&|x| x[0] < 0.25 && x[1] < 0.25), median_where(&|x| x[0] > 0.7 && x[1] > 0.7)]
    };
    let range = ["--min-size", "0.02", "--max-size", "0.05"];
    let [box_before, far_before] = medians(&range);
    let [in_box, far] = medians(&[&range[..], &["--refine-box", "-1,-1,0.3,0.3,0.02"]].concat());
    assert!(in_box < 0.025 && in_box < 0.8 * box_before, "box median {in_box}, without the box {box_before}");
    assert!((far / far_before - 1.0).abs() < 0.15, "far median {far}, without the box {far_before}");
    for refine in ["0,0,0,1,1,1,0.02", "0,0,1,1", "0,0,0.3,0.3,0.01"] {
        let output = mesh_square(&["--min-size", "0.02", "--refine-box", refine]);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(
            !output.status.success() && stderr.contains("--refine-box") && !stderr.contains("panicked"),
            "{stderr}"
        );
    }

    // A refined face: the elements along one side of the square (face 1, the outer ring's first
    // side) take its size, the other outer sides keep theirs. A face the geometry lacks is an
    // error listing the faces it has.
    let side_medians = |knobs: &[&str]| {
        let output = mesh_square(knobs);
        assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
        let mesh = amber_mesh::read_mesh::<2>(&final_mesh).unwrap();
        // The middle thirds: a corner's elements, finer on one side, would weigh on the other's.
        let middle = |t: f64| (0.33..0.67).contains(&t);
        let sides: [&dyn Fn([f64; 2]) -> bool; 4] = [
            &|x| x[1] < 0.04 && middle(x[0]),
            &|x| x[0] > 0.96 && middle(x[1]),
            &|x| x[1] > 0.96 && middle(x[0]),
            &|x| x[0] < 0.04 && middle(x[1]),
        ];
        sides.map(|inside| {
            let mut h: Vec<f64> =
                mesh.midpoints().iter().zip(mesh.sizes()).filter(|(x, _)| inside(**x)).map(|(_, h)| h).collect();
            h.sort_by(f64::total_cmp);
            h[h.len() / 2]
        })
    };
    let before = side_medians(&range);
    let after = side_medians(&[&range[..], &["--refine-face", "1,0.02"]].concat());
    let refined: Vec<usize> = (0..4).filter(|&k| after[k] < 0.025 && after[k] < 0.8 * before[k]).collect();
    assert_eq!(refined.len(), 1, "side medians {after:?}, without the face {before:?}");
    let opposite = (refined[0] + 2) % 4;
    assert!((after[opposite] / before[opposite] - 1.0).abs() < 0.15, "{after:?}, without the face {before:?}");
    // The faces to choose from: the square's four sides and the hole's four, with their lengths.
    let output = mesh_square(&["--list-faces"]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let listed = String::from_utf8_lossy(&output.stdout);
    let lengths: Vec<f64> = listed
        .lines()
        .map(|line| line.split("length ").nth(1).and_then(|rest| rest.split(',').next()).unwrap().parse().unwrap())
        .collect();
    assert!(listed.starts_with("face 1: ") && listed.contains("face 8: "), "{listed}");
    assert_eq!(lengths.iter().map(|l| (l * 10.0).round() as i64).collect::<Vec<_>>(), [10, 10, 10, 10, 2, 2, 2, 2]);

    // A refinement beyond the model's budget: the user's cap (--max-elements) decides, not the
    // model's budget, which guards only the model's own field.
    let fine = ["--refine-face", "1,0.006"];
    let output = mesh_square(&fine);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let elements = amber_mesh::read_mesh::<2>(&final_mesh).unwrap().num_elements();
    let output = mesh_square(&[&fine[..], &["--max-elements", &(elements / 2).to_string()]].concat());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success() && stderr.contains("--max-elements"), "{elements} elements: {stderr}");
    let cases = [
        ("99,0.02", "its faces are 1–8"),
        ("1", "FACE,SIZE"),
        ("1,-0.5", "positive"),
        ("inlet,0.02", "names no faces"),
    ];
    for (refine, expected) in cases {
        let output = mesh_square(&["--refine-face", refine]);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(
            !output.status.success() && stderr.contains("--refine-face") && stderr.contains(expected),
            "{refine}: {stderr}"
        );
    }

    // A missing model, or a Poisson model without its load, is an error with a message.
    for args in [vec!["--model", "/nonexistent", "--problem"], vec!["square", "--model"]] {
        let mut command = amber();
        command.arg("mesh").args(&args);
        if args.contains(&"--problem") {
            command.arg(&problem_file);
        } else {
            command.arg(&run);
        }
        let output = command.arg("-o").arg(&final_mesh).output().unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(!output.status.success() && !stderr.contains("panicked"), "{args:?}: {stderr}");
        assert!(stderr.contains("/nonexistent") || stderr.contains("--problem"), "{args:?}: {stderr}");
    }
}

/// `amber evaluate --model MODEL --data DATA --out OUT`, which must succeed; its evaluation.json.
fn evaluate(model: &std::path::Path, data: &std::path::Path, out: &std::path::Path) -> serde_json::Value {
    let output =
        amber().args(["evaluate", "--model"]).arg(model).arg("--data").arg(data).arg("--out").arg(out).output();
    let output = output.unwrap();
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    serde_json::from_str(&std::fs::read_to_string(out.join("evaluation.json")).unwrap()).unwrap()
}

/// `dir/config.json`: a tiny network (width 8, two message-passing steps, two generation steps)
/// checkpointed every 10 steps, with the config members `fields` besides.
fn tiny_model_config(dir: &std::path::Path, fields: &str) -> std::path::PathBuf {
    let config = dir.join("config.json");
    let json = format!(
        r#"{{"checkpoint_interval": 10, "inference_steps": 2, "network": {{"latent_dim": 8, "message_passing_steps": 2}}, {fields}}}"#
    );
    std::fs::write(&config, json).unwrap();
    config
}

/// `amber train --profile smoke --steps STEPS --data DATA --config CONFIG --out RUN`.
fn train_smoke_folder(
    data: &std::path::Path,
    config: &std::path::Path,
    run: impl AsRef<std::ffi::OsStr>,
    steps: u64,
) -> std::process::Output {
    let mut command = amber();
    command.args(["train", "--profile", "smoke", "--steps", &steps.to_string()]);
    command.arg("--data").arg(data).arg("--config").arg(config).arg("--out").arg(run).output().unwrap()
}

/// A folder dataset end to end: the project's demo plates (2D `.msh` experts, no geometry files)
/// train a tiny model, which is evaluated on the test split (JSON, Markdown, a picture per part)
/// and meshes one of its plates from the plate's boundary alone.
#[test]
fn trains_and_evaluates_a_folder_of_expert_meshes() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("plates");
    amber_tasks::folder::write_demo_dataset(&data, 1).unwrap();
    let config = tiny_model_config(dir.path(), r#""validation_interval": 10"#);
    let run = dir.path().join("run");
    let output = train_smoke_folder(&data, &config, &run, 30);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    // The last validation line scores the saved model, its last generation step fitted.
    let last = stderr.lines().rfind(|l| l.contains("validation at step")).unwrap_or_default();
    assert!(last.contains("step 30 with the last generation step fitted"), "{stderr}");
    let card: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("model/card.json")).unwrap()).unwrap();
    assert_eq!(card["task"], serde_json::json!({"folder": {"dimension": 2}}));
    assert!(card["initial_size"].as_f64().unwrap() > 0.05, "{card}");

    let out = dir.path().join("evaluation");
    let evaluation = evaluate(&run, &data.join("test"), &out);
    let parts = evaluation["parts"].as_array().unwrap();
    assert_eq!(parts.len(), 2);
    for part in parts {
        let last = part["evaluation"]["steps"].as_array().unwrap().last().unwrap()["metrics"].clone();
        assert!(last["normalised_dcd"].as_f64().unwrap().is_finite(), "{part}");
        assert!(last["elements"].as_u64().unwrap() > 0 && part["evaluation"]["expert_elements"].as_u64().unwrap() > 0);
        assert!(std::fs::metadata(out.join(part["picture"].as_str().unwrap())).unwrap().len() > 1000);
        let ratios = ["p10", "median", "p90"].map(|q| part["size_ratios"][q].as_f64().unwrap());
        assert!(ratios[0] > 0.0 && ratios[0] <= ratios[1] && ratios[1] <= ratios[2], "{part}");
    }
    let table = std::fs::read_to_string(out.join("evaluation.md")).unwrap();
    assert!(table.contains("| test/plate00 |") && table.contains("**mean**"), "{table}");
    println!("{table}");
    let predictor: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("model/predictor.json")).unwrap()).unwrap();
    let trained_scale = predictor["limits"]["final_step_scale"].as_f64().unwrap();
    assert!(trained_scale != 1.0 && trained_scale > 0.0, "training fits the scale: {trained_scale}");

    // Calibrated on the test plates, the model meshes them with their experts' counts (in the
    // geometric mean over parts).
    let calibrate = |model: &std::path::Path, out: &std::path::Path, flags: &[&str]| {
        let mut command = amber();
        command.args(["calibrate", "--model"]).arg(model).arg("--data").arg(data.join("test")).arg("-o").arg(out);
        let output = command.args(flags).output().unwrap();
        assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
        let predictor = std::fs::read_to_string(out.join("predictor.json")).unwrap();
        serde_json::from_str::<serde_json::Value>(&predictor).unwrap()["limits"]["final_count"].clone()
    };
    let calibrated = dir.path().join("calibrated");
    assert!(
        calibrate(&run, &calibrated, &[])["slope"].is_number(),
        "the folder profile's count regression is refitted"
    );
    // The card says how and on what the new predictor was fitted.
    let card: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(calibrated.join("card.json")).unwrap()).unwrap();
    let fitted: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(calibrated.join("predictor.json")).unwrap()).unwrap();
    let calibration = &card["calibration"];
    assert_eq!(calibration["data"], data.join("test").display().to_string(), "{card}");
    assert_eq!(calibration["final_step_scale"], fitted["limits"]["final_step_scale"], "{card}");
    assert_eq!(calibration["count_regression_slope"], fitted["limits"]["final_count"]["slope"], "{card}");
    assert!(calibration["command"].as_str().unwrap().contains("calibrate") && card["evaluation"].is_null());
    // A model trained without the count regression gains one only when asked.
    let plain = dir.path().join("plain");
    std::fs::create_dir(&plain).unwrap();
    for file in std::fs::read_dir(run.join("model")).unwrap() {
        let file = file.unwrap().path();
        std::fs::copy(&file, plain.join(file.file_name().unwrap())).unwrap();
    }
    let mut predictor = predictor;
    predictor["limits"].as_object_mut().unwrap().remove("final_count");
    std::fs::write(plain.join("predictor.json"), predictor.to_string()).unwrap();
    assert!(calibrate(&plain, &dir.path().join("scale-only"), &[]).is_null());
    let slope = calibrate(&plain, &dir.path().join("regressed"), &["--count-regression"])["slope"].as_f64();
    assert!(slope.is_some_and(|s| (0.0..=1.0).contains(&s)), "{slope:?}");
    let evaluation = evaluate(&calibrated, &data.join("test"), &dir.path().join("evaluation-calibrated"));
    let log_ratios: Vec<f64> = evaluation["parts"]
        .as_array()
        .unwrap()
        .iter()
        .map(|part| {
            let last = part["evaluation"]["steps"].as_array().unwrap().last().unwrap()["metrics"]["elements"].clone();
            (last.as_f64().unwrap() / part["evaluation"]["expert_elements"].as_f64().unwrap()).ln()
        })
        .collect();
    let ratio = (log_ratios.iter().sum::<f64>() / log_ratios.len() as f64).exp();
    assert!((ratio - 1.0).abs() < 0.1, "calibrated counts / experts' {ratio}");

    let mesh = dir.path().join("plate.vtu");
    let plate = data.join("test/plate00.msh");
    let mut command = amber();
    command.arg("mesh").arg(&plate).arg("--model").arg(&run).arg("--expert").arg(&plate).arg("-o").arg(&mesh);
    let output = command.output().unwrap();
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let expert = amber_mesh::read_mesh::<2>(&plate).unwrap();
    let (generated, cells) = amber_mesh::read_mesh_with_data::<2>(&mesh).unwrap();
    assert!((generated.total_volume() - expert.total_volume()).abs() < 1e-9);
    // The final mesh carries where it is coarser or finer than the expert's.
    let field = &cells.cell["log_size_ratio_to_expert"];
    let expected = amber_metrics::log_size_ratios(&generated, &expert);
    assert!(field.iter().zip(&expected).all(|(a, b)| (a - b).abs() < 1e-9) && field.len() == expected.len());
    assert!(!String::from_utf8_lossy(&output.stderr).contains("units"));

    // The same plate in units a thousand times larger than the model's: meshed, with a warning.
    let shrunk = dir.path().join("shrunk.vtu");
    let scaled: Vec<[f64; 2]> = expert.vertices().iter().map(|p| [p[0] * 1e-3, p[1] * 1e-3]).collect();
    let tiny = amber_mesh::Mesh2::new(scaled, expert.cells().to_vec()).unwrap();
    amber_mesh::write_mesh(&tiny, &shrunk, &amber_mesh::MeshData::new()).unwrap();
    let output = amber().arg("mesh").arg(&shrunk).arg("--model").arg(&run).arg("-o").arg(&mesh).output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success() && stderr.contains("in the units of the model's training parts"), "{stderr}");

    // A 2D model on a folder of tet meshes is an error naming both.
    let solids = dir.path().join("solids");
    std::fs::create_dir_all(&solids).unwrap();
    let tet =
        amber_mesh::Mesh3::new(vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], vec![0, 1, 2, 3]);
    amber_mesh::write_mesh(&tet.unwrap(), solids.join("tet.vtu"), &amber_mesh::MeshData::new()).unwrap();
    let output = amber().args(["evaluate", "--model"]).arg(&run).arg("--data").arg(&solids).output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success() && stderr.contains("holds 3D meshes") && stderr.contains("in 2D"), "{stderr}");

    // A folder with a split missing is an error naming it, not a panic.
    std::fs::remove_dir_all(data.join("val")).unwrap();
    let output = train_smoke_folder(&data, &config, dir.path().join("run2"), 30);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success() && stderr.contains("val") && !stderr.contains("panicked"), "{stderr}");

    // A dataset folder of held-out parts alone (no train/) is evaluated on its test/.
    std::fs::remove_dir_all(data.join("train")).unwrap();
    let evaluation = evaluate(&run, &data, &dir.path().join("evaluation-test-only"));
    assert_eq!(evaluation["parts"].as_array().unwrap().len(), 2);
}

/// `amber cross-validate` on the demo plates: a model per fold, each scoring the plates it held
/// out, pooled into one table that lists every training plate once with its fold. Run again, it
/// reuses the fold models and writes the same scores; other folds into the same directory, or
/// more folds than parts, are refused with the reason.
#[test]
fn cross_validates_a_folder_of_expert_meshes() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("plates");
    amber_tasks::folder::write_demo_dataset(&data, 3).unwrap();
    let config = tiny_model_config(dir.path(), r#""validation_interval": 0"#);
    let out = dir.path().join("cv");
    let cross_validate = |folds: &str| {
        let mut command = amber();
        command.args(["cross-validate", "--profile", "smoke", "--steps", "20", "--folds", folds, "--data"]);
        command.arg(&data).arg("--config").arg(&config).arg("--out").arg(&out).output().unwrap()
    };
    let output = cross_validate("3");
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let json = std::fs::read_to_string(out.join("evaluation.json")).unwrap();
    let evaluation: serde_json::Value = serde_json::from_str(&json).unwrap();
    let parts = evaluation["parts"].as_array().unwrap();
    let names: Vec<&str> = parts.iter().map(|p| p["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["train/plate00", "train/plate01", "train/plate02"]);
    let mut total = 0.0;
    for (k, (part, fold)) in parts.iter().zip(evaluation["folds"].as_array().unwrap()).enumerate() {
        // Three plates in three folds: fold k holds out plate k alone and scores it.
        assert_eq!(part["fold"], k);
        assert_eq!(fold["held_out"], serde_json::json!([names[k]]));
        let score = part["evaluation"]["steps"].as_array().unwrap().last().unwrap()["metrics"]["normalised_dcd"]
            .as_f64()
            .unwrap();
        assert_eq!(fold["normalised_dcd"].as_f64().unwrap(), score);
        total += score;
        assert!(std::fs::metadata(out.join(part["picture"].as_str().unwrap())).unwrap().len() > 1000);
        let card = std::fs::read_to_string(out.join(format!("fold{k}/model/card.json"))).unwrap();
        assert!(card.contains(&format!("fold {k} of 3 holds out {}", names[k])), "{card}");
    }
    assert!((evaluation["normalised_dcd"].as_f64().unwrap() - total / 3.0).abs() < 1e-12);
    let table = std::fs::read_to_string(out.join("evaluation.md")).unwrap();
    assert!(table.contains("| train/plate01 | 1 | ") && table.contains("| **all** | 3 parts |"), "{table}");
    println!("{table}");

    let output = cross_validate("3");
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    assert_eq!(std::fs::read_to_string(out.join("evaluation.json")).unwrap(), json, "the same models, the same scores");

    let output = cross_validate("2");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success() && stderr.contains("held_out.json") && stderr.contains("new --out"), "{stderr}");
    let output = cross_validate("4");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success() && stderr.contains("takes 2 to 3 folds"), "{stderr}");

    // A folder of training parts alone cross-validates without validation.
    std::fs::remove_dir_all(&out).unwrap();
    std::fs::remove_dir_all(data.join("val")).unwrap();
    let output = cross_validate("2");
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    assert!(String::from_utf8_lossy(&output.stdout).contains("without validation"));
    let evaluation: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("evaluation.json")).unwrap()).unwrap();
    assert_eq!(evaluation["folds"][0]["held_out"], serde_json::json!(["train/plate00", "train/plate02"]));
}

/// Parts' own inputs (`<stem>.inputs.json`) train into a model that names them; meshing a new part
/// with that model needs them (`--problem`), and without them the error says so.
#[test]
fn a_model_of_parts_with_inputs_meshes_a_part_given_its_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("plates");
    amber_tasks::folder::write_demo_dataset(&data, 2).unwrap();
    for split in ["train", "val", "test"] {
        for entry in std::fs::read_dir(data.join(split)).unwrap() {
            let mesh = entry.unwrap().path();
            let stem = mesh.file_stem().unwrap().to_str().unwrap().to_owned();
            let inputs = r#"{"clamp": [0.0, 0.5], "load": 2.0}"#;
            std::fs::write(data.join(split).join(format!("{stem}.inputs.json")), inputs).unwrap();
        }
    }
    let config = tiny_model_config(
        dir.path(),
        r#""validation_interval": 0, "inputs": ["log_size", "log_boundary_distance", "load", "log_distance_to_clamp"]"#,
    );
    let run = dir.path().join("run");
    let output = train_smoke_folder(&data, &config, &run, 10);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));

    let plate = data.join("test/plate00.msh");
    let mesh = || {
        let mut command = amber();
        command.arg("mesh").arg(&plate).arg("--model").arg(&run).arg("-o").arg(dir.path().join("p.vtu"));
        command
    };
    let output = mesh().output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        !output.status.success() && stderr.contains("load, log_distance_to_clamp") && stderr.contains("--problem"),
        "{stderr}"
    );
    let output = mesh().arg("--problem").arg(data.join("test/plate00.inputs.json")).output().unwrap();
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
}

/// Every model shipped in `models/` loads and meshes a geometry of its task from the geometry
/// alone (a Poisson model with a load, no expert); reads `../shared/` for the Console surface.
#[test]
fn every_shipped_model_meshes_a_geometry_of_its_task() {
    let models = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models");
    let dir = tempfile::tempdir().unwrap();
    let mut names: Vec<_> = std::fs::read_dir(&models).unwrap().map(|e| e.unwrap().file_name()).collect();
    names.sort();
    assert!(!names.is_empty(), "no shipped models in {}", models.display());
    for name in names {
        let name = name.to_str().unwrap();
        let card: serde_json::Value =
            serde_json::from_slice(&std::fs::read(models.join(name).join("card.json")).unwrap()).unwrap();
        let out = dir.path().join(format!("{name}.vtu"));
        let mut command = amber();
        command.args(["mesh", "--steps", "1", "--model", name, "-o"]).arg(&out).env("AMBER_MODELS", &models);
        let volume = match card["task"].as_str() {
            Some("poisson") => {
                let problem = dir.path().join("load.json");
                std::fs::write(
                    &problem,
                    r#"{"domain": {"polygon": [[0,0],[1,0],[1,0.5],[0.5,0.5],[0.5,1],[0,1]]},
                        "load": {"means": [[0.3, 0.3]], "covariances": [[[0.001, 0], [0, 0.001]]], "weights": [1.0]}}"#,
                )
                .unwrap();
                command.arg("--problem").arg(&problem);
                0.75
            }
            Some("console") => {
                let Some(data) = amber_testdata::shared("data/console") else { continue };
                let stl = data.join("reference_surface/val/001.stl");
                command.arg(&stl);
                amber_meshgen::mesh3d::Surface::load(&stl, amber_mesh::StlFaceIds::FromFile)
                    .unwrap()
                    .0
                    .enclosed_volume()
            }
            other => panic!("{name}: a card of an unknown task {other:?}"),
        };
        let output = command.output().unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(output.status.success(), "{name}: {stderr}");
        let total = match card["task"].as_str() {
            Some("poisson") => amber_mesh::read_mesh::<2>(&out).unwrap().total_volume(),
            _ => amber_mesh::read_mesh::<3>(&out).unwrap().total_volume(),
        };
        assert!((total / volume - 1.0).abs() < 5e-3, "{name}: volume {total} for {volume}");
    }
    // An expert mesh as the geometry has no CAD faces: they are found at its sharp and tangent
    // edges, as many as the part's CAD model has (11 for val/002).
    let Some(data) = amber_testdata::shared("data/console") else { return };
    let output = amber()
        .args(["mesh", "--model", "console", "--list-faces"])
        .arg(data.join("val/002.nas"))
        .env("AMBER_MODELS", &models)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&output.stdout);
    let cad = amber_meshgen::mesh3d::Surface::load(
        data.join("reference_surface/val/002.stl"),
        amber_mesh::StlFaceIds::FromFile,
    )
    .unwrap()
    .0;
    let mut cad_faces = cad.face_ids().to_vec();
    cad_faces.sort();
    cad_faces.dedup();
    let found = stdout.lines().filter(|line| line.starts_with("face ")).count();
    assert!(output.status.success() && found == cad_faces.len(), "{found} faces, CAD {}: {stdout}", cad_faces.len());
}

/// A STEP file is a geometry like its gmsh-made reference surface: `amber mesh part.step`
/// tessellates it through gmsh and fills it, and the `.msh` groups the boundary by CAD face.
/// Reads `../shared/`; needs gmsh.
#[test]
fn meshes_a_step_file_through_gmsh() {
    let Some(data) = amber_testdata::shared("data/console") else { return };
    if amber_tasks::cad::Gmsh::default().version().is_none() {
        return amber_testdata::skip("gmsh is not on the PATH (`pip install gmsh`)");
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("part.msh");
    let output =
        amber().args(["mesh", "--size", "3"]).arg(data.join("val/002.step")).arg("-o").arg(&out).output().unwrap();
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let reference = amber_meshgen::mesh3d::Surface::load(
        data.join("reference_surface/val/002.stl"),
        amber_mesh::StlFaceIds::FromFile,
    )
    .unwrap()
    .0
    .enclosed_volume();
    let (mesh, written) = amber_mesh::read_mesh_with_data::<3>(&out).unwrap();
    let total = mesh.total_volume();
    assert!((total / reference - 1.0).abs() < 5e-3, "volume {total} for {reference}");
    // One physical group per CAD face, over the whole boundary.
    let info: serde_json::Value =
        serde_json::from_slice(&std::fs::read(data.join("reference_surface/val/002.json")).unwrap()).unwrap();
    let faces = info["faces"].as_array().unwrap().len();
    let groups: std::collections::BTreeSet<i32> = written.facet_tags.values().copied().collect();
    assert_eq!(groups.len(), faces, "{groups:?}");
    let boundary = amber_mesh::FacetAdjacency::new(&mesh).unwrap().boundary_facets().count();
    assert_eq!(written.facet_tags.len(), boundary);
}
