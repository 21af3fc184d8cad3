//! The environment's images in memory: the equirectangular source, cube maps (face after face,
//! row after row, texel (f, i, j) at (f·M + j)·M + i, RGBA f32 with A = 1), and the prefiltered
//! set the renderer samples.

/// Linear RGB radiance, equirectangular (SPEC §4), row 0 at the top (v = 0, +Y).
#[derive(Clone, Debug, PartialEq)]
pub struct Equirect {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 3]>,
}

impl Equirect {
    /// A constant environment (white furnace tests).
    pub fn constant(width: u32, height: u32, rgb: [f32; 3]) -> Self {
        Self {
            width,
            height,
            pixels: vec![rgb; (width as usize) * (height as usize)],
        }
    }

    /// Builds a map by evaluating `radiance(direction)` at every pixel centre.
    pub fn from_fn(width: u32, height: u32, radiance: impl Fn(glam::DVec3) -> [f32; 3]) -> Self {
        let mut pixels = Vec::with_capacity((width as usize) * (height as usize));
        for y in 0..height {
            for x in 0..width {
                let u = (f64::from(x) + 0.5) / f64::from(width);
                let v = (f64::from(y) + 0.5) / f64::from(height);
                pixels.push(radiance(super::cube::equirect_to_direction(u, v)));
            }
        }
        Self {
            width,
            height,
            pixels,
        }
    }

    pub fn get(&self, x: u32, y: u32) -> [f32; 3] {
        self.pixels[(y as usize) * (self.width as usize) + x as usize]
    }
}

/// A cube map of RGBA f32 texels in Vulkan face order.
#[derive(Clone, Debug, PartialEq)]
pub struct CubeImage {
    pub face_size: u32,
    pub texels: Vec<[f32; 4]>,
}

impl CubeImage {
    pub fn new(face_size: u32) -> Self {
        let n = face_size as usize;
        Self {
            face_size,
            texels: vec![[0.0, 0.0, 0.0, 1.0]; 6 * n * n],
        }
    }

    pub fn index(&self, face: usize, i: u32, j: u32) -> usize {
        let m = self.face_size as usize;
        (face * m + j as usize) * m + i as usize
    }

    pub fn get(&self, face: usize, i: u32, j: u32) -> [f32; 4] {
        self.texels[self.index(face, i, j)]
    }

    /// The six faces side by side (+X, −X, +Y, −Y, +Z, −Z), width 6M, height M: the layout of
    /// `shikki prefilter`'s EXR files.
    pub fn to_strip(&self) -> crate::output::HdrImage {
        let m = self.face_size;
        let mut strip = crate::output::HdrImage::new(6 * m, m);
        for face in 0..6 {
            for j in 0..m {
                for i in 0..m {
                    strip.set(face as u32 * m + i, j, self.get(face, i, j));
                }
            }
        }
        strip
    }
}

/// Everything the renderer samples: K layers (layer 0 sharp) with their β, and irradiance.
#[derive(Clone, Debug, PartialEq)]
pub struct PrefilteredEnvironment {
    pub betas: Vec<f64>,
    pub layers: Vec<CubeImage>,
    pub irradiance: CubeImage,
}
