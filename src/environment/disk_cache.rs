//! On-disk cache of prefiltered environments: a second run with the same environment loads its
//! layers and irradiance from a file instead of prefiltering again (on lavapipe the prefilter is
//! most of a render's start-up).
//!
//! * **Where.** `<cache root>/environments/<key>.shkenv`, the cache root being the directory of the
//!   pipeline cache (`SHIKKI_PIPELINE_CACHE`, default `~/.cache/shikki/`): `SHIKKI_PIPELINE_CACHE=0`
//!   disables both, `SHIKKI_ENV_CACHE=0` only this one. A context without a pipeline cache (every
//!   test) has no environment cache either.
//! * **Key.** SHA-256 of the decoded source pixels (so the embedded `builtin:studio` and any file
//!   are covered alike, and a changed decoder cannot serve stale data), the prefilter parameters,
//!   intensity, rotation, the file-format version and the shikki version.
//! * **Trust.** Nothing in a file is trusted: the header's magic, version and sizes are checked
//!   against limits before any allocation, the payload's SHA-256 must match, the key stored inside
//!   must be the one asked for, and every layer must have the size the parameters imply. A file
//!   failing any check is ignored with a [`Warning`] for the caller (and rewritten by the next
//!   prefilter).
//! * **Writes** are atomic (`output::atomic`): a crash never leaves a torn cache file.

use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};

use super::image::{CubeImage, Equirect, PrefilteredEnvironment};
use super::params::{EnvironmentLight, PrefilterParams};
use crate::{Error, Result, Warning};

const MAGIC: &[u8; 8] = b"SHKENV\r\n";
const FORMAT_VERSION: u32 = 1;
/// magic, version, key (32), payload length (8), payload SHA-256 (32).
const HEADER_BYTES: usize = 8 + 4 + 32 + 8 + 32;
/// Larger files are not read: face 4096 with 20 layers is far below this, a hostile or damaged
/// file cannot make us allocate more.
const MAX_FILE_BYTES: u64 = 4 << 30;
const EXTENSION: &str = "shkenv";

/// The directory holding cached environments.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EnvironmentDiskCache {
    dir: PathBuf,
}

/// The identity of one prefiltered environment (SHA-256, see the module doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CacheKey([u8; 32]);

impl CacheKey {
    pub fn new(source: &Equirect, params: &PrefilterParams, light: EnvironmentLight) -> Self {
        let mut hash = Sha256::new();
        hash.update(b"shikki prefiltered environment\0");
        hash.update(env!("CARGO_PKG_VERSION").as_bytes());
        hash.update(FORMAT_VERSION.to_le_bytes());
        hash.update(source.width.to_le_bytes());
        hash.update(source.height.to_le_bytes());
        hash.update(bytemuck::cast_slice::<[f32; 3], u8>(&source.pixels));
        hash.update(params.face_size.to_le_bytes());
        hash.update(params.layers.to_le_bytes());
        hash.update(params.fine_layers.to_le_bytes());
        hash.update([u8::from(params.blur_net_of_read)]);
        hash.update(params.supersample(source.width).to_le_bytes());
        for x in [
            params.beta_min,
            params.beta_max,
            params.layer_texel,
            light.intensity,
            light.rotation_deg,
        ] {
            hash.update(x.to_bits().to_le_bytes());
        }
        // Every layer as planned, so that a change to the rule that sizes or blurs them (as
        // `small_layer_texel` was) is a new key and not a stale file.
        for layer in params.plan() {
            hash.update(layer.beta.to_bits().to_le_bytes());
            hash.update(layer.blur.to_bits().to_le_bytes());
            hash.update(layer.face_size.to_le_bytes());
        }
        CacheKey(hash.finalize().into())
    }

    pub fn hex(&self) -> String {
        self.0.iter().map(|b| format!("{b:02x}")).collect()
    }
}

impl EnvironmentDiskCache {
    pub fn new(dir: impl Into<PathBuf>) -> Self {
        Self { dir: dir.into() }
    }

    /// The cache beside a pipeline cache file (see the module doc); `None` without one or with
    /// `SHIKKI_ENV_CACHE=0`.
    pub fn beside_pipeline_cache(pipeline_cache: Option<&Path>) -> Option<Self> {
        if std::env::var_os("SHIKKI_ENV_CACHE").is_some_and(|v| v == "0") {
            return None;
        }
        let root = pipeline_cache?.parent()?;
        Some(Self::new(root.join("environments")))
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }

    pub fn path(&self, key: &CacheKey) -> PathBuf {
        self.dir.join(format!("{}.{EXTENSION}", key.hex()))
    }

    /// The cached environment for `key`, if a valid file exists. A missing file is silent; an
    /// invalid one is ignored with a warning in `warnings`.
    pub fn load(
        &self,
        key: &CacheKey,
        params: &PrefilterParams,
        warnings: &mut Vec<Warning>,
    ) -> Option<PrefilteredEnvironment> {
        let path = self.path(key);
        let size = std::fs::metadata(&path).ok()?.len();
        let result = if size > MAX_FILE_BYTES {
            Err(format!("{size} bytes is more than any valid cache file"))
        } else {
            std::fs::read(&path)
                .map_err(|e| e.to_string())
                .and_then(|bytes| decode(&bytes, key, params))
        };
        match result {
            Ok(env) => Some(env),
            Err(reason) => {
                warnings.push(Warning::CacheFileInvalid { path, reason });
                None
            }
        }
    }

    /// Writes `env` under `key` atomically, creating the directory.
    pub fn store(&self, key: &CacheKey, env: &PrefilteredEnvironment) -> Result<()> {
        std::fs::create_dir_all(&self.dir).map_err(|e| Error::Write {
            path: self.dir.clone(),
            message: format!("cannot create the environment cache directory: {e}"),
        })?;
        crate::output::atomic::write_atomically(&self.path(key), &encode(key, env))
    }
}

/// The file's bytes: header, then the payload (layer count, betas, each layer's face size and
/// texels, the irradiance's face size and texels), all little-endian. Written into one buffer of
/// the final size, the digest filled in last: a cold render writes three of these while it holds
/// the environments, so a payload copy or a doubling buffer would set its peak memory.
pub fn encode(key: &CacheKey, env: &PrefilteredEnvironment) -> Vec<u8> {
    let cubes = || env.layers.iter().chain(std::iter::once(&env.irradiance));
    let payload_len = 4
        + 8 * env.betas.len()
        + cubes()
            .map(|cube| 4 + 16 * cube.texels.len())
            .sum::<usize>();
    let mut bytes = Vec::with_capacity(HEADER_BYTES + payload_len);
    bytes.extend_from_slice(MAGIC);
    bytes.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    bytes.extend_from_slice(&key.0);
    bytes.extend_from_slice(&(payload_len as u64).to_le_bytes());
    // The payload's SHA-256, once the payload is there.
    bytes.extend_from_slice(&[0; 32]);
    bytes.extend_from_slice(&(env.layers.len() as u32).to_le_bytes());
    for beta in &env.betas {
        bytes.extend_from_slice(&beta.to_le_bytes());
    }
    for cube in cubes() {
        bytes.extend_from_slice(&cube.face_size.to_le_bytes());
        for texel in &cube.texels {
            for c in texel {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    let digest = Sha256::digest(&bytes[HEADER_BYTES..]);
    bytes[HEADER_BYTES - 32..HEADER_BYTES].copy_from_slice(&digest);
    bytes
}

/// Parses and checks a cache file (see the module doc); the error says which check failed.
pub fn decode(
    bytes: &[u8],
    key: &CacheKey,
    params: &PrefilterParams,
) -> std::result::Result<PrefilteredEnvironment, String> {
    let mut reader = Reader { bytes, at: 0 };
    if reader.take(8)? != MAGIC {
        return Err("not a shikki environment cache file".into());
    }
    let version = reader.u32()?;
    if version != FORMAT_VERSION {
        return Err(format!(
            "format version {version}, expected {FORMAT_VERSION}"
        ));
    }
    if reader.take(32)? != key.0 {
        return Err("it belongs to another environment".into());
    }
    let payload_len = reader.u64()?;
    let checksum = reader.take(32)?.to_vec();
    let payload = reader.rest();
    if payload.len() as u64 != payload_len {
        return Err(format!(
            "truncated or padded: {} payload bytes, header says {payload_len}",
            payload.len()
        ));
    }
    if Sha256::digest(payload).as_slice() != checksum.as_slice() {
        return Err("checksum mismatch (damaged file)".into());
    }
    let mut reader = Reader {
        bytes: payload,
        at: 0,
    };
    let plan = params.plan();
    let layer_count = reader.u32()? as usize;
    if layer_count != plan.len() {
        return Err(format!(
            "{layer_count} layers, the parameters give {}",
            plan.len()
        ));
    }
    let mut betas = Vec::with_capacity(layer_count);
    for _ in 0..layer_count {
        betas.push(reader.f64()?);
    }
    let expected_faces = plan
        .iter()
        .map(|l| l.face_size)
        .chain(std::iter::once(params.irradiance_face()));
    let mut cubes = Vec::with_capacity(layer_count + 1);
    for expected in expected_faces {
        let face_size = reader.u32()?;
        if face_size != expected {
            return Err(format!("a face of {face_size} texels, expected {expected}"));
        }
        let count = 6 * (face_size as usize) * (face_size as usize);
        let raw = reader.take(count * 16)?;
        let mut texels = Vec::with_capacity(count);
        for chunk in raw.chunks_exact(16) {
            let mut texel = [0.0f32; 4];
            for (c, b) in texel.iter_mut().zip(chunk.chunks_exact(4)) {
                *c = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
            }
            if !texel.iter().all(|c| c.is_finite()) {
                return Err("a texel is not finite".into());
            }
            texels.push(texel);
        }
        cubes.push(CubeImage { face_size, texels });
    }
    if !reader.rest().is_empty() {
        return Err("trailing bytes after the irradiance".into());
    }
    let irradiance = cubes
        .pop()
        .ok_or_else(|| "no irradiance cube".to_string())?;
    Ok(PrefilteredEnvironment {
        betas,
        layers: cubes,
        irradiance,
    })
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> std::result::Result<&'a [u8], String> {
        let end = self
            .at
            .checked_add(n)
            .filter(|&end| end <= self.bytes.len())
            .ok_or_else(|| "truncated".to_string())?;
        let slice = &self.bytes[self.at..end];
        self.at = end;
        Ok(slice)
    }

    fn rest(&mut self) -> &'a [u8] {
        let slice = &self.bytes[self.at..];
        self.at = self.bytes.len();
        slice
    }

    fn u32(&mut self) -> std::result::Result<u32, String> {
        let b = self.take(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    fn u64(&mut self) -> std::result::Result<u64, String> {
        let mut a = [0u8; 8];
        a.copy_from_slice(self.take(8)?);
        Ok(u64::from_le_bytes(a))
    }

    fn f64(&mut self) -> std::result::Result<f64, String> {
        let mut a = [0u8; 8];
        a.copy_from_slice(self.take(8)?);
        let x = f64::from_le_bytes(a);
        if x.is_finite() {
            Ok(x)
        } else {
            Err("a layer β is not finite".into())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> (CacheKey, PrefilterParams, PrefilteredEnvironment) {
        let params = PrefilterParams {
            face_size: 16,
            layers: 2,
            beta_min: 0.5,
            beta_max: 1.0,
            layer_texel: 1.0,
            small_layer_texel: 1.0,
            fine_layers: 0,
            blur_net_of_read: false,
            supersample_scale: 1,
        };
        let source = Equirect::constant(4, 2, [1.0, 0.5, 0.25]);
        let key = CacheKey::new(&source, &params, EnvironmentLight::default());
        let cube = |face: u32, v: f32| CubeImage {
            face_size: face,
            texels: (0..6 * face * face)
                .map(|i| [v, i as f32, 0.0, 1.0])
                .collect(),
        };
        let plan = params.plan();
        let env = PrefilteredEnvironment {
            betas: plan.iter().map(|l| l.beta).collect(),
            layers: plan.iter().map(|l| cube(l.face_size, 2.0)).collect(),
            irradiance: cube(params.irradiance_face(), 3.0),
        };
        (key, params, env)
    }

    #[test]
    fn round_trip_is_exact() {
        let (key, params, env) = sample();
        let back = decode(&encode(&key, &env), &key, &params).unwrap();
        assert_eq!(back, env);
    }

    #[test]
    fn key_changes_with_every_input() {
        let (key, params, _) = sample();
        let source = Equirect::constant(4, 2, [1.0, 0.5, 0.25]);
        let other_pixels = Equirect::constant(4, 2, [1.0, 0.5, 0.26]);
        let light = |intensity, rotation_deg| EnvironmentLight {
            intensity,
            rotation_deg,
        };
        assert_eq!(key, CacheKey::new(&source, &params, light(1.0, 0.0)));
        assert_ne!(key, CacheKey::new(&other_pixels, &params, light(1.0, 0.0)));
        assert_ne!(key, CacheKey::new(&source, &params, light(2.0, 0.0)));
        assert_ne!(key, CacheKey::new(&source, &params, light(1.0, 90.0)));
        let more_layers = PrefilterParams {
            layers: 3,
            ..params
        };
        assert_ne!(key, CacheKey::new(&source, &more_layers, light(1.0, 0.0)));
        let finer_layers = PrefilterParams {
            layer_texel: 0.5,
            small_layer_texel: 0.5,
            ..params
        };
        assert_ne!(key, CacheKey::new(&source, &finer_layers, light(1.0, 0.0)));
        let fine_layers = PrefilterParams {
            fine_layers: 1,
            ..params
        };
        assert_ne!(key, CacheKey::new(&source, &fine_layers, light(1.0, 0.0)));
        let net_of_read = PrefilterParams {
            blur_net_of_read: !params.blur_net_of_read,
            ..params
        };
        assert_ne!(key, CacheKey::new(&source, &net_of_read, light(1.0, 0.0)));
        let supersampled = PrefilterParams {
            supersample_scale: 4,
            ..params
        };
        assert_ne!(key, CacheKey::new(&source, &supersampled, light(1.0, 0.0)));
    }

    #[test]
    fn damaged_files_are_rejected_with_a_reason() {
        let (key, params, env) = sample();
        let good = encode(&key, &env);
        let mut flipped = good.clone();
        let last = flipped.len() - 1;
        flipped[last] ^= 1;
        assert!(decode(&flipped, &key, &params)
            .unwrap_err()
            .contains("checksum"));
        assert!(decode(&good[..good.len() - 5], &key, &params)
            .unwrap_err()
            .contains("truncated"));
        assert!(decode(b"garbage", &key, &params).is_err());
        let other_key = CacheKey([7; 32]);
        assert!(decode(&good, &other_key, &params)
            .unwrap_err()
            .contains("another environment"));
        let other_params = PrefilterParams {
            face_size: 32,
            ..params
        };
        assert!(decode(&good, &key, &other_params).is_err());
    }

    #[test]
    fn store_then_load_and_ignore_a_corrupt_file() {
        let dir =
            std::env::temp_dir().join(format!("shikki-env-cache-test-{}", std::process::id()));
        let cache = EnvironmentDiskCache::new(&dir);
        let (key, params, env) = sample();
        cache.store(&key, &env).unwrap();
        let mut warnings = Vec::new();
        assert_eq!(cache.load(&key, &params, &mut warnings), Some(env));
        assert!(warnings.is_empty(), "{warnings:?}");
        std::fs::write(cache.path(&key), b"SHKENV\r\n broken").unwrap();
        assert_eq!(cache.load(&key, &params, &mut warnings), None);
        assert!(
            matches!(&warnings[..], [Warning::CacheFileInvalid { path, .. }] if *path == cache.path(&key)),
            "one warning names the ignored file: {warnings:?}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
