//! The OBJ encoder: a header comment, one `o`, then `v x y z`, `vn x y z` and `f a//a b//b c//c`
//! lines (1-based; the normal index is the vertex index, so tobj and other readers share vertices
//! exactly as the mesh does).
//!
//! Numbers are Rust's `Display` of the f32: the shortest decimal that parses back to the same
//! f32 (`0.1`, `-0.70710677`), never in exponent form, which some OBJ readers do not accept. The
//! round trip through text is therefore exact, not within a tolerance.

use std::fmt::Write;

use crate::raster::mesh::Mesh;

pub(super) fn encode(mesh: &Mesh, name: &str) -> String {
    // ~30 bytes per `v`/`vn` line and ~40 per face line at typical magnitudes.
    let mut text = String::with_capacity(60 * mesh.positions.len() + 40 * mesh.triangle_count());
    // `write!` to a String cannot fail; its Result is only there for the trait.
    let _ = writeln!(
        text,
        "# {name}, written by shikki {}: {} vertices, {} triangles\n\
         # +Y up, 1 unit = 10 cm, counter-clockwise front faces, smooth vertex normals",
        env!("CARGO_PKG_VERSION"),
        mesh.positions.len(),
        mesh.triangle_count()
    );
    let _ = writeln!(text, "o {}", object_name(name));
    for [x, y, z] in &mesh.positions {
        let _ = writeln!(text, "v {x} {y} {z}");
    }
    for [x, y, z] in &mesh.normals {
        let _ = writeln!(text, "vn {x} {y} {z}");
    }
    for triangle in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [triangle[0], triangle[1], triangle[2]].map(|i| u64::from(i) + 1);
        let _ = writeln!(text, "f {a}//{a} {b}//{b} {c}//{c}");
    }
    text
}

/// OBJ's `o` takes the rest of the line: whitespace and `#` would split or end the name.
fn object_name(name: &str) -> String {
    let cleaned: String = name
        .chars()
        .map(|c| {
            if c.is_whitespace() || c.is_control() || c == '#' {
                '_'
            } else {
                c
            }
        })
        .collect();
    if cleaned.is_empty() {
        "mesh".into()
    } else {
        cleaned
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_board_is_written_line_by_line() {
        let text = encode(&crate::raster::mesh::board(), "board");
        let body: Vec<&str> = text.lines().filter(|l| !l.starts_with('#')).collect();
        assert_eq!(
            body,
            [
                "o board",
                "v -1 0 -1",
                "v -1 0 1",
                "v 1 0 1",
                "v 1 0 -1",
                "vn 0 1 0",
                "vn 0 1 0",
                "vn 0 1 0",
                "vn 0 1 0",
                "f 1//1 2//2 3//3",
                "f 1//1 3//3 4//4",
            ]
        );
    }

    #[test]
    fn display_of_f32_parses_back_to_the_same_bits() {
        // The values the shortest round-trip must get right: subnormals, the largest finite
        // value, a sign bit on zero, and awkward decimals.
        for x in [
            0.1f32,
            -0.707_106_77,
            f32::MIN_POSITIVE,
            1e-45,
            f32::MAX,
            -0.0,
            1.0 / 3.0,
            16_777_217.0,
        ] {
            let text = format!("{x}");
            assert!(!text.contains('e'), "{text}");
            assert_eq!(
                text.parse::<f32>().unwrap().to_bits(),
                x.to_bits(),
                "{text}"
            );
        }
    }

    #[test]
    fn object_names_stay_on_one_word() {
        assert_eq!(object_name("lacquer bowl#2\n"), "lacquer_bowl_2_");
        assert_eq!(object_name(""), "mesh");
    }
}
