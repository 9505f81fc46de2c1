//! Wavefront OBJ meshes: a line-by-line check that names the line of a bad vertex or face
//! (tobj reports neither), then tobj for the geometry.

use crate::shapes::{RawMesh, is_closed, signed_volume};
use crate::{SceneError, SceneErrorKind};
use glam::DVec3;
use std::collections::HashMap;

/// A mesh read from an OBJ file, in the file's coordinates.
pub(crate) struct ObjMesh {
    /// Positions, triangles (fans of the polygons) and, if the file has `vn` for every face
    /// corner, one normal per vertex (positions are split where a position has several).
    pub raw: RawMesh,
    /// Whether the winding was reversed because the closed mesh enclosed a negative volume.
    pub flipped: bool,
}

fn invalid(file: &str, line: Option<usize>, message: String) -> SceneError {
    SceneError {
        file: file.to_string(),
        line,
        key: None,
        message,
        kind: SceneErrorKind::Invalid,
    }
}

/// Checks the `v`, `vn`, `vt` and `f` lines of an OBJ text: coordinates must parse as finite
/// single-precision numbers, face indices must be non-zero integers within the counts of
/// their kind (positive indices against the whole file, negative ones against the lines so
/// far), and a face must have three corners or more. Errors carry the 1-based line number. Returns whether every face corner names a
/// normal (`f v//vn` or `f v/vt/vn`), so that `vn` can be used as given.
fn check_lines(file: &str, text: &str) -> Result<bool, SceneError> {
    // Totals first: positive face indices may refer to any element of the file.
    let mut totals = [0i64; 3]; // v, vt, vn
    for line in text.lines() {
        match line.split_whitespace().next() {
            Some("v") => totals[0] += 1,
            Some("vt") => totals[1] += 1,
            Some("vn") => totals[2] += 1,
            _ => {}
        }
    }
    let mut seen = [0i64; 3];
    let (mut corners, mut corners_with_normal) = (0usize, 0usize);
    for (i, line) in text.lines().enumerate() {
        let lineno = i + 1;
        let mut tokens = line.split_whitespace();
        let Some(tag) = tokens.next() else { continue };
        match tag {
            "v" | "vn" => {
                let what = if tag == "v" { "vertex" } else { "normal" };
                let mut count = 0;
                for tok in tokens.by_ref().take(3) {
                    count += 1;
                    let value: f32 = tok.parse().map_err(|_| {
                        invalid(
                            file,
                            Some(lineno),
                            format!("malformed {what} coordinate `{tok}`"),
                        )
                    })?;
                    if !value.is_finite() {
                        return Err(invalid(
                            file,
                            Some(lineno),
                            format!(
                                "{what} coordinate `{tok}` is not finite (NaN, infinite or \
                                 beyond single precision)"
                            ),
                        ));
                    }
                }
                if count < 3 {
                    return Err(invalid(
                        file,
                        Some(lineno),
                        format!("{what} with {count} coordinates (3 needed)"),
                    ));
                }
                seen[if tag == "v" { 0 } else { 2 }] += 1;
            }
            "vt" => seen[1] += 1,
            "f" => {
                // A face needs three corners: fewer is a cut or garbled line (a file
                // truncated mid-face, say), never a degenerate triangle to drop.
                let count = line.split_whitespace().count() - 1;
                if count < 3 {
                    return Err(invalid(
                        file,
                        Some(lineno),
                        format!(
                            "face with {count} corner{} (3 or more needed): is the file cut \
                             short?",
                            if count == 1 { "" } else { "s" }
                        ),
                    ));
                }
                for tok in tokens {
                    corners += 1;
                    if tok.split('/').nth(2).is_some_and(|n| !n.is_empty()) {
                        corners_with_normal += 1;
                    }
                    for (k, part) in tok.split('/').enumerate().take(3) {
                        if part.is_empty() && k > 0 {
                            continue;
                        }
                        let (kind, tag) = [
                            ("vertex", "v"),
                            ("texture coordinate", "vt"),
                            ("normal", "vn"),
                        ][k];
                        let idx: i64 = part.parse().map_err(|_| {
                            invalid(file, Some(lineno), format!("malformed face index `{tok}`"))
                        })?;
                        let ok = if idx > 0 {
                            idx <= totals[k]
                        } else {
                            idx < 0 && -idx <= seen[k]
                        };
                        if !ok {
                            return Err(invalid(
                                file,
                                Some(lineno),
                                format!(
                                    "face {kind} index {idx} is out of range: the file has {} \
                                     `{tag}` lines{}",
                                    totals[k],
                                    if idx < 0 {
                                        format!(" ({} before this line)", seen[k])
                                    } else {
                                        String::new()
                                    }
                                ),
                            ));
                        }
                    }
                }
            }
            _ => {}
        }
    }
    Ok(corners > 0 && corners_with_normal == corners)
}

/// `bytes` with every point (`p`) and line (`l`) element emptied, the line breaks kept (so
/// line numbers do not move).
fn without_points_and_lines(bytes: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(bytes.len());
    for line in bytes.split_inclusive(|&b| b == b'\n') {
        let tag = line
            .split(|b| b.is_ascii_whitespace())
            .find(|t| !t.is_empty());
        if matches!(tag, Some(b"p") | Some(b"l")) {
            out.extend(line.iter().filter(|&&b| b == b'\n' || b == b'\r'));
        } else {
            out.extend_from_slice(line);
        }
    }
    out
}

/// Reads an OBJ file's bytes (`file` names it in errors): checks the lines, loads the
/// geometry with tobj (polygons fanned into triangles, all groups and objects merged into one
/// mesh, materials ignored), keeps `vn` normals when every face corner has one, and reverses
/// the winding of a closed mesh whose signed volume is negative.
pub(crate) fn parse(file: &str, bytes: &[u8]) -> Result<ObjMesh, SceneError> {
    let text = String::from_utf8_lossy(bytes);
    let normals_everywhere = check_lines(file, &text)?;
    // `..Default::default()` covers the fields tobj's optional features add (`merging`,
    // `reordering`), should feature unification turn them on.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ..Default::default()
    };
    // Point and line elements are blanked before tobj reads the file, rather than left to
    // its `ignore_points` / `ignore_lines`: the latter drops two-vertex lines only, so a
    // polyline `l 1 2 3` came back as a triangle.
    let faces_only = without_points_and_lines(bytes);
    let (models, _materials) = tobj::load_obj_buf(&mut &faces_only[..], &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| invalid(file, None, format!("malformed OBJ: {e}")))?;

    let mut positions: Vec<DVec3> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    // Per corner: the normal, when the file gives one for every corner.
    let mut corner_normals: Vec<DVec3> = Vec::new();
    let mut all_normals = true;
    for model in &models {
        let m = &model.mesh;
        let base = positions.len() as u32;
        positions.extend(
            m.positions
                .chunks_exact(3)
                .map(|c| DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64)),
        );
        let has_normals = normals_everywhere
            && !m.normals.is_empty()
            && m.normal_indices.len() == m.indices.len();
        all_normals &= has_normals;
        for (t, tri) in m.indices.chunks_exact(3).enumerate() {
            triangles.push([base + tri[0], base + tri[1], base + tri[2]]);
            if has_normals {
                for k in 0..3 {
                    let ni = m.normal_indices[3 * t + k] as usize;
                    let n = m
                        .normals
                        .get(3 * ni..3 * ni + 3)
                        .map(|c| DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64))
                        .unwrap_or(DVec3::ZERO);
                    corner_normals.push(n);
                }
            }
        }
    }

    // Orientation: a closed surface must enclose a positive volume with outward winding.
    let flipped = is_closed(&triangles) && signed_volume(&positions, &triangles) < 0.0;
    if flipped {
        for (t, tri) in triangles.iter_mut().enumerate() {
            tri.swap(1, 2);
            if all_normals && !corner_normals.is_empty() {
                corner_normals.swap(3 * t + 1, 3 * t + 2);
            }
        }
    }

    let raw = if all_normals && !corner_normals.is_empty() {
        // One vertex per (position, normal) pair.
        let mut ids: HashMap<(u32, [u64; 3]), u32> = HashMap::new();
        let mut split_pos = Vec::new();
        let mut split_nrm = Vec::new();
        let mut split_tris = Vec::with_capacity(triangles.len());
        for (t, tri) in triangles.iter().enumerate() {
            let mut out = [0u32; 3];
            for k in 0..3 {
                let n = corner_normals[3 * t + k];
                let key = (tri[k], n.to_array().map(f64::to_bits));
                out[k] = *ids.entry(key).or_insert_with(|| {
                    split_pos.push(positions[tri[k] as usize]);
                    split_nrm.push(n);
                    (split_pos.len() - 1) as u32
                });
            }
            split_tris.push(out);
        }
        RawMesh {
            positions: split_pos,
            normals: Some(split_nrm),
            triangles: split_tris,
        }
    } else {
        RawMesh {
            positions,
            normals: None,
            triangles,
        }
    };
    Ok(ObjMesh { raw, flipped })
}
