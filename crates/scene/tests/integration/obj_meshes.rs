//! OBJ meshes: loading (fans, `vn` normals, mesh directories, inside-out meshes turned
//! around), degenerate triangles dropped and counted, and errors naming the file and line
//! (bad numbers and indices, missing and unreadable files).

use crate::common::{HEAD, area, check_mesh, line_of, no_dirs, volume};
use glam::DVec3;
use sss_scene::{LoadOptions, Scene, SceneError, SceneErrorKind, load};
use std::path::{Path, PathBuf};

/// A fresh, empty directory under the system temporary directory.
fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("sss-scene-tests-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

/// A scene (in `dir`) with one mesh object naming `file`.
fn mesh_scene(file: &str) -> String {
    format!("{HEAD}\n[[objects]]\nmaterial = \"m\"\nshape = \"mesh\"\nfile = \"{file}\"\n")
}

/// Loads `scene.toml` written to `dir` with `text`.
fn load_in(dir: &Path, text: &str, opts: &LoadOptions) -> Result<Scene, SceneError> {
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).expect("write scene");
    load(&path, opts)
}

const TETRA: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

#[test]
fn obj_meshes_load() {
    let dir = temp_dir("obj-load");
    std::fs::write(dir.join("tetra.obj"), TETRA).unwrap();
    let s = load_in(&dir, &mesh_scene("tetra.obj"), &no_dirs()).unwrap();
    let m = &s.objects[0].mesh;
    check_mesh(m);
    assert_eq!(m.triangles.len(), 4);
    assert!((volume(m) - 1.0 / 6.0).abs() < 1e-7);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    // Area-weighted smooth normals: the origin vertex's normal is -(1,1,1)/√3 by symmetry.
    let origin = m.positions.iter().position(|p| *p == DVec3::ZERO).unwrap();
    assert!((m.normals[origin] + DVec3::ONE.normalize()).length() < 1e-7);

    // A unit cube of quads is fanned into 12 triangles.
    let cube = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
                f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
    std::fs::write(dir.join("cube.obj"), cube).unwrap();
    let s = load_in(&dir, &mesh_scene("cube.obj"), &no_dirs()).unwrap();
    let m = &s.objects[0].mesh;
    check_mesh(m);
    assert_eq!(m.triangles.len(), 12);
    assert!((volume(m) - 1.0).abs() < 1e-7);
    assert!((area(m) - 6.0).abs() < 1e-7);

    // Normals from `vn` are used as given (normalised), each at its own corner, also where
    // they are not the face's normal.
    let with_vn = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 2\nvn 1 0 1\nvn 0 1 1\nf 1//1 2//2 3//3\n";
    std::fs::write(dir.join("vn.obj"), with_vn).unwrap();
    let s = load_in(&dir, &mesh_scene("vn.obj"), &no_dirs()).unwrap();
    let m = &s.objects[0].mesh;
    let given = |p: DVec3| {
        let n = DVec3::new(p.x, p.y, 1.0);
        n / n.length()
    };
    assert_eq!(m.positions.len(), 3);
    for (p, n) in m.positions.iter().zip(&m.normals) {
        assert!((*n - given(*p)).length() < 1e-12, "{p}: {n}");
    }
    // Relative (negative) indices count back from the line: the same triangle and normals.
    let relative = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 2\nvn 1 0 1\nvn 0 1 1\n\
                    f -3/-3/-3 -2/-2/-2 -1/-1/-1\n";
    std::fs::write(dir.join("relative.obj"), relative).unwrap();
    let s = load_in(&dir, &mesh_scene("relative.obj"), &no_dirs()).unwrap();
    let r = &s.objects[0].mesh;
    assert_eq!(
        (&r.positions, &r.normals, &r.triangles),
        (&m.positions, &m.normals, &m.triangles)
    );

    // Faces without normals among ones with: the `vn` are ignored, normals computed.
    let mixed = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 1 0 0\nf 1//1 2//1 3//1\nf 2 4 3\n";
    std::fs::write(dir.join("mixed.obj"), mixed).unwrap();
    let s = load_in(&dir, &mesh_scene("mixed.obj"), &no_dirs()).unwrap();
    assert_eq!(s.objects[0].mesh.positions.len(), 4);
    assert!(
        s.objects[0]
            .mesh
            .normals
            .iter()
            .all(|n| (*n - DVec3::Z).length() < 1e-12)
    );

    // Found in the second mesh directory when not next to the scene.
    let other = temp_dir("obj-load-dirs");
    std::fs::write(other.join("elsewhere.obj"), TETRA).unwrap();
    let opts = LoadOptions {
        mesh_dirs: vec![dir.join("missing-subdir"), other.clone()],
    };
    let s = load_in(&dir, &mesh_scene("elsewhere.obj"), &opts).unwrap();
    assert_eq!(s.objects[0].mesh.triangles.len(), 4);
    // An inside-out closed mesh is turned around, with a warning.
    let inverted = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 4 2\nf 1 3 4\nf 2 4 3\n";
    std::fs::write(dir.join("inverted.obj"), inverted).unwrap();
    let s = load_in(&dir, &mesh_scene("inverted.obj"), &no_dirs()).unwrap();
    assert!(volume(&s.objects[0].mesh) > 0.0);
    assert_eq!(s.warnings.len(), 1);
    assert!(s.warnings[0].contains("inverted.obj") && s.warnings[0].contains("reversed"));
    // Point (`p`) and line (`l`) elements are ignored, polylines too: only the faces make
    // triangles.
    std::fs::write(
        dir.join("points.obj"),
        format!("{TETRA}p 1 2\nl 1 2\n  l 1 2 3 4\n"),
    )
    .unwrap();
    let s = load_in(&dir, &mesh_scene("points.obj"), &no_dirs()).unwrap();
    assert_eq!(s.objects[0].mesh.triangles.len(), 4);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    // An open surface is never turned around, whatever the sign of Σ a·(b × c): this
    // triangle's is −1, and it keeps its winding (normal −z) without a warning.
    std::fs::write(dir.join("open.obj"), "v 0 0 1\nv 0 1 1\nv 1 0 1\nf 1 2 3\n").unwrap();
    let s = load_in(&dir, &mesh_scene("open.obj"), &no_dirs()).unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert!(
        s.objects[0]
            .mesh
            .normals
            .iter()
            .all(|n| (*n + DVec3::Z).length() < 1e-12)
    );
    // The same with a `vn` per vertex: turned around, each corner keeps its own normal.
    let normals = [
        [-1.0, -1.0, -1.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    let inverted_vn = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n\
                       vn -1 -1 -1\nvn 1 0 0\nvn 0 1 0\nvn 0 0 1\n\
                       f 1//1 2//2 3//3\nf 1//1 4//4 2//2\nf 1//1 3//3 4//4\nf 2//2 4//4 3//3\n";
    std::fs::write(dir.join("inverted-vn.obj"), inverted_vn).unwrap();
    let s = load_in(&dir, &mesh_scene("inverted-vn.obj"), &no_dirs()).unwrap();
    let m = &s.objects[0].mesh;
    assert!(volume(m) > 0.0);
    assert_eq!(m.positions.len(), 4);
    let corners = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
    for (p, n) in m.positions.iter().zip(&m.normals) {
        let i = corners
            .iter()
            .position(|c| c == p)
            .expect("a tetrahedron corner");
        let want = DVec3::from_array(normals[i]).normalize();
        assert!((*n - want).length() < 1e-12, "{p}: {n}, want {want}");
    }
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&other);
}

#[test]
fn obj_degenerate_triangles_are_dropped_and_counted() {
    let dir = temp_dir("obj-degenerate");
    // The tetrahedron, a triangle repeating a vertex, and a collinear (zero-area) one.
    let text = format!("{TETRA}v 2 0 0\nf 1 1 2\nf 1 2 5\n");
    std::fs::write(dir.join("degen.obj"), text).unwrap();
    let s = load_in(&dir, &mesh_scene("degen.obj"), &no_dirs()).unwrap();
    let m = &s.objects[0].mesh;
    check_mesh(m);
    assert_eq!(m.triangles.len(), 4);
    assert_eq!(m.positions.len(), 4, "the unused vertex is removed");
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
    assert!(s.warnings[0].contains("degen.obj"), "{}", s.warnings[0]);
    assert!(
        s.warnings[0].contains("dropped 2 degenerate"),
        "{}",
        s.warnings[0]
    );

    // Nothing left: an error naming the mesh file.
    std::fs::write(dir.join("flat.obj"), "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n").unwrap();
    let e = load_in(&dir, &mesh_scene("flat.obj"), &no_dirs()).unwrap_err();
    assert_eq!(e.kind, SceneErrorKind::Invalid);
    assert!(e.file.ends_with("flat.obj"), "{e}");
    assert!(
        e.message.contains("no triangles left after dropping 1"),
        "{e}"
    );
    std::fs::write(dir.join("points.obj"), "v 0 0 0\nv 1 0 0\n").unwrap();
    let e = load_in(&dir, &mesh_scene("points.obj"), &no_dirs()).unwrap_err();
    assert!(
        e.file.ends_with("points.obj") && e.message.contains("no triangles"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn obj_errors_name_the_file_and_line() {
    let dir = temp_dir("obj-errors");
    let cases: [(&str, &str, usize, &[&str]); 12] = [
        (
            "nan.obj",
            "v 0 0 0\nv 1 0 0\n# c\nv 0 nan 0\nf 1 2 3\n",
            4,
            &["vertex coordinate", "nan", "not finite"],
        ),
        (
            "vn-nan.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 nan 1\nf 1//1 2//1 3//1\n",
            4,
            &["normal coordinate", "nan", "not finite"],
        ),
        (
            "no-vertex.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf /1 2 3\n",
            5,
            &["malformed face index", "/1"],
        ),
        (
            "inf.obj",
            "v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n",
            2,
            &["inf", "not finite"],
        ),
        (
            "huge.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1e40 0\nf 1 2 3\n",
            3,
            &["1e40", "not finite"],
        ),
        (
            "face.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n",
            4,
            &["malformed face index", "x"],
        ),
        (
            "range.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n",
            5,
            &["out of range", "9"],
        ),
        (
            "behind.obj",
            "v 0 0 0\nv 1 0 0\nf -3 -2 -1\nv 0 1 0\n",
            3,
            &["out of range", "-3", "2 before this line"],
        ),
        (
            "behind-vn.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//-1 2//-1 3//-2\n",
            5,
            &["normal index -2", "out of range", "1 before this line"],
        ),
        (
            // A file cut mid-face (the bunny's `f 1787 1413`): an error, not a dropped
            // degenerate triangle.
            "cut.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 3 2",
            5,
            &["face with 2 corners", "cut short"],
        ),
        (
            "bare-f.obj",
            "v 0 0 0\nf\nv 1 0 0\n",
            2,
            &["face with 0 corners"],
        ),
        (
            "short.obj",
            "v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n",
            2,
            &["2 coordinates"],
        ),
    ];
    for (file, text, line, words) in cases {
        std::fs::write(dir.join(file), text).unwrap();
        let e = load_in(&dir, &mesh_scene(file), &no_dirs()).unwrap_err();
        assert_eq!(e.kind, SceneErrorKind::Invalid, "{e}");
        assert!(e.file.ends_with(file), "{e}");
        assert_eq!(e.line, Some(line), "{e}");
        for w in words {
            assert!(e.to_string().contains(w), "`{w}` not in {e}");
        }
    }
    // An error only tobj finds (a malformed texture coordinate) still names the file.
    std::fs::write(
        dir.join("vt.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt a b\nf 1 2 3\n",
    )
    .unwrap();
    let e = load_in(&dir, &mesh_scene("vt.obj"), &no_dirs()).unwrap_err();
    assert!(
        e.file.ends_with("vt.obj") && e.message.contains("malformed OBJ"),
        "{e}"
    );

    // Missing: kind MeshNotFound, the scene's line and key, every directory searched.
    let opts = LoadOptions {
        mesh_dirs: vec![
            PathBuf::from("/nonexistent/a"),
            PathBuf::from("/nonexistent/b"),
        ],
    };
    let text = mesh_scene("nowhere.obj");
    let e = load_in(&dir, &text, &opts).unwrap_err();
    assert_eq!(e.kind, SceneErrorKind::MeshNotFound, "{e}");
    assert!(e.file.ends_with("scene.toml"));
    assert_eq!(e.line, Some(line_of(&text, "nowhere.obj")));
    assert_eq!(e.key.as_deref(), Some("objects[0].file"));
    for w in [
        "nowhere.obj",
        &dir.display().to_string(),
        "/nonexistent/a",
        "/nonexistent/b",
    ] {
        assert!(e.message.contains(w), "`{w}` not in {e}");
    }
    // Unreadable (a directory): kind Io, naming the path.
    std::fs::create_dir_all(dir.join("folder.obj")).unwrap();
    let e = load_in(&dir, &mesh_scene("folder.obj"), &no_dirs()).unwrap_err();
    assert_eq!(e.kind, SceneErrorKind::Io, "{e}");
    assert!(e.file.ends_with("folder.obj"), "{e}");
    // A missing scene file: kind Io.
    let e = load(&dir.join("no-such-scene.toml"), &no_dirs()).unwrap_err();
    assert_eq!(e.kind, SceneErrorKind::Io, "{e}");
    assert!(e.file.ends_with("no-such-scene.toml"));
    let _ = std::fs::remove_dir_all(&dir);
}
