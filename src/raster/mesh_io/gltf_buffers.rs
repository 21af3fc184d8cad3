//! The bytes around a glTF document: the GLB container (glTF 2.0 §4.4) and buffer sources
//! (the GLB BIN chunk, base64 `data:` URIs, external files relative to the glTF file).
//!
//! Done here rather than by the `gltf` crate because its GLB header parsing underflows on a
//! short declared length and its URI decoding unwraps invalid UTF-8: a hostile file would panic
//! the renderer. Every length here is checked. Owns nothing else.

use std::path::Path;

use ::gltf::buffer::Source;
use ::gltf::Document;

use super::{check_file_length, content_error};
use crate::Result;

const GLB_MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

/// The JSON text and the optional BIN chunk of a GLB file, or the whole input as JSON.
pub(super) fn split_container<'b>(
    path: &Path,
    bytes: &'b [u8],
) -> Result<(&'b [u8], Option<Vec<u8>>)> {
    if !bytes.starts_with(GLB_MAGIC) {
        return Ok((bytes, None));
    }
    let fail = |message: String| content_error(path, format!("not a valid GLB file: {message}"));
    let word = |at: usize| -> Option<u32> {
        let b = bytes.get(at..at.checked_add(4)?)?;
        Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let (Some(version), Some(length)) = (word(4), word(8)) else {
        return Err(fail("the 12-byte header is cut short".into()));
    };
    if version != 2 {
        return Err(fail(format!(
            "version {version}; shikki reads glTF 2.0 (GLB version 2)"
        )));
    }
    let end = length as usize;
    if end < 12 || end > bytes.len() {
        return Err(fail(format!(
            "the header declares {length} bytes but the file has {}",
            bytes.len()
        )));
    }
    let mut json = None;
    let mut bin = None;
    let mut at = 12;
    while at < end {
        let (Some(chunk_length), Some(chunk_type)) = (word(at), word(at + 4)) else {
            return Err(fail(format!("chunk header at byte {at} is cut short")));
        };
        let start = at + 8;
        let stop = start
            .checked_add(chunk_length as usize)
            .filter(|&stop| stop <= end)
            .ok_or_else(|| fail(format!("chunk at byte {at} runs past the end of the file")))?;
        match chunk_type {
            CHUNK_JSON if json.is_none() && at == 12 => json = Some(&bytes[start..stop]),
            CHUNK_BIN if json.is_some() && bin.is_none() => bin = Some(bytes[start..stop].to_vec()),
            // Unknown chunks are skipped, as the specification requires.
            _ => {}
        }
        at = stop;
    }
    let json = json.ok_or_else(|| fail("the first chunk is not JSON".into()))?;
    Ok((json, bin))
}

/// Every buffer's bytes, at least `byteLength` long, resolved against the glTF file's folder.
pub(super) fn load_buffers(
    path: &Path,
    document: &Document,
    mut blob: Option<Vec<u8>>,
) -> Result<Vec<Vec<u8>>> {
    let base = path.parent().unwrap_or_else(|| Path::new("."));
    let mut buffers = Vec::new();
    for buffer in document.buffers() {
        let index = buffer.index();
        let fail = |message: String| content_error(path, format!("buffer {index}: {message}"));
        let data = match buffer.source() {
            Source::Bin => blob.take().ok_or_else(|| {
                fail("refers to the GLB BIN chunk, which this file does not have".into())
            })?,
            Source::Uri(uri) => read_uri(base, uri).map_err(fail)?,
        };
        if data.len() < buffer.length() {
            return Err(fail(format!(
                "byteLength is {} but only {} bytes are there",
                buffer.length(),
                data.len()
            )));
        }
        buffers.push(data);
    }
    Ok(buffers)
}

fn read_uri(base: &Path, uri: &str) -> std::result::Result<Vec<u8>, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let Some((_, payload)) = rest.split_once(";base64,") else {
            return Err("only base64 data: URIs are supported".into());
        };
        return decode_base64(payload);
    }
    let is_scheme = |s: &str| {
        // RFC 3986: ALPHA *( ALPHA / DIGIT / "+" / "-" / "." ); one letter is a Windows drive.
        s.len() > 1
            && s.starts_with(|c: char| c.is_ascii_alphabetic())
            && s.chars()
                .all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
    };
    let relative = match uri.split_once(':') {
        Some((scheme, _)) if is_scheme(scheme) => {
            return Err(format!(
                "URI {uri:?} has a scheme shikki does not fetch; use a file next to the glTF"
            ))
        }
        _ => percent_decode(uri)?,
    };
    let file = base.join(relative);
    check_file_length(&file).map_err(|e| format!("{e} (URI {uri:?})"))?;
    std::fs::read(&file).map_err(|e| format!("cannot read {} (URI {uri:?}): {e}", file.display()))
}

/// RFC 3986 percent-decoding of a relative reference, which must decode to UTF-8.
fn percent_decode(uri: &str) -> std::result::Result<String, String> {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = bytes
                .get(i + 1..i + 3)
                .and_then(|h| std::str::from_utf8(h).ok())
                .and_then(|h| u8::from_str_radix(h, 16).ok())
                .ok_or_else(|| format!("URI {uri:?} has a malformed %-escape"))?;
            out.push(hex);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).map_err(|_| format!("URI {uri:?} does not decode to UTF-8"))
}

/// RFC 4648 base64 (standard alphabet; padding optional, whitespace not allowed).
fn decode_base64(text: &str) -> std::result::Result<Vec<u8>, String> {
    let text = text.trim_end_matches('=');
    let mut out = Vec::with_capacity(text.len() / 4 * 3 + 2);
    let mut accumulator = 0u32;
    let mut bits = 0;
    for (position, c) in text.bytes().enumerate() {
        let value = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => {
                return Err(format!(
                    "the base64 data: URI has an invalid character {:?} at position {position}",
                    c as char
                ))
            }
        };
        accumulator = accumulator << 6 | u32::from(value);
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((accumulator >> bits) as u8);
            accumulator &= (1 << bits) - 1;
        }
    }
    if bits >= 6 {
        return Err("the base64 data: URI has a dangling character".into());
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_decodes_rfc4648_vectors() {
        // RFC 4648 §10 test vectors, with and without padding.
        for (encoded, plain) in [
            ("", ""),
            ("Zg==", "f"),
            ("Zm8=", "fo"),
            ("Zm9v", "foo"),
            ("Zm9vYg==", "foob"),
            ("Zm9vYmE", "fooba"),
            ("Zm9vYmFy", "foobar"),
        ] {
            assert_eq!(
                decode_base64(encoded).unwrap(),
                plain.as_bytes(),
                "{encoded}"
            );
        }
        // All 6-bit values: "+/" are 62, 63 → 0xFB, 0xFF… by hand: "//8=" = 111111 111111 111100.
        assert_eq!(decode_base64("//8=").unwrap(), vec![0xFF, 0xFF]);
        assert!(decode_base64("Zm9v!").unwrap_err().contains("position 4"));
        assert!(decode_base64("Z").is_err());
    }

    #[test]
    fn percent_decoding_handles_escapes_and_refuses_bad_ones() {
        assert_eq!(percent_decode("my%20mesh.bin").unwrap(), "my mesh.bin");
        assert_eq!(percent_decode("a%2Fb").unwrap(), "a/b");
        assert!(percent_decode("bad%2").is_err());
        assert!(percent_decode("bad%zz").is_err());
        assert!(percent_decode("bad%FF").is_err()); // not UTF-8
    }

    #[test]
    fn glb_container_lengths_are_checked() {
        let path = Path::new("t.glb");
        let mut glb = b"glTF".to_vec();
        glb.extend(2u32.to_le_bytes());
        glb.extend(24u32.to_le_bytes()); // 12 header + 8 chunk header + 4 JSON
        glb.extend(4u32.to_le_bytes());
        glb.extend(CHUNK_JSON.to_le_bytes());
        glb.extend(b"{}  ");
        let (json, bin) = split_container(path, &glb).unwrap();
        assert_eq!((json, bin), (&b"{}  "[..], None));
        // Declared total below the header size, above the file size, a chunk past the end.
        for (at, value) in [(8, 4u32), (8, 25), (12, 5)] {
            let mut broken = glb.clone();
            broken[at..at + 4].copy_from_slice(&value.to_le_bytes());
            assert!(split_container(path, &broken).is_err(), "{at}: {value}");
        }
        assert!(split_container(path, &glb[..10]).is_err());
        // Plain JSON passes through.
        assert_eq!(split_container(path, b"{}").unwrap().0, b"{}");
    }
}
