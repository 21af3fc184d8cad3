//! `contact_sheet.png`: the jobs' images as small tiles with their id and swept values written
//! under each, so a person sees the sweep at a glance.
//!
//! Owns thumbnails (downsampled, tone-mapped like the job's PNG), the sheet layout and its
//! drawing. Text is DejaVu Sans (assets/fonts) through plotters, as in the fit plots.
//!
//! The sheet is bounded whatever the batch: at most [`MAX_SHEET_TILES`] tiles (beyond that, one
//! job in every `stride`, evenly through the run, with a line saying so: the manifest lists every
//! job) and labels of at most [`MAX_LABEL_VALUES`] values, each cut to the tile's width. A sheet
//! of every tile grew with the batch, held every tile until the end, and once its byte count
//! wrapped `u32` plotters panicked (BENCHMARKS.md, "The batch at scale"). Its buffer is allocated
//! once, at most 3,208 × 5,279 pixels; each tile is painted into it as its job finishes and then
//! dropped, so only the tiles waiting for the writer are held.

use std::panic::{catch_unwind, AssertUnwindSafe};

use plotters::backend::RGBPixel;
use plotters::prelude::*;

use super::manifest::{ManifestRow, STATUS_OK};
use crate::output::text::FONT_FAMILY;
use crate::output::tonemap::Srgb8Encoder;
use crate::output::{HdrImage, PngSettings};
use crate::{Error, Result};

/// The longest side of a tile's image, in pixels.
pub const TILE: u32 = 192;
const LINE_HEIGHT: u32 = 15;
const FONT_SIZE: u32 = 12;
const GAP: u32 = 8;
/// Where the image is transparent, tiles show this grey (sRGB 8-bit), like an image viewer.
const BACKDROP: [u8; 3] = [128, 128, 128];
/// The most tiles on one sheet: 16 × 16, which shows a typical sweep whole and keeps the sheet
/// near 3,200 × 5,300 pixels (50 MB while drawn) — beyond that a sheet is too large to view.
pub const MAX_SHEET_TILES: usize = 256;
/// Swept values a label lists; further ones are counted on one more line (the manifest has them).
pub const MAX_LABEL_VALUES: usize = 6;
/// Characters of a label line measured at most: longer ones are cut before measuring, so a
/// swept value of megabytes costs nothing.
const MAX_LABEL_CHARS: usize = 64;

/// A tile image, RGB8 rows top first.
#[derive(Clone, Debug)]
pub struct Thumbnail {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<[u8; 3]>,
}

impl Thumbnail {
    /// Box-filtered to fit in [`TILE`]², then exposure → tone curve → sRGB, composited over the
    /// backdrop by coverage.
    pub fn from_hdr(image: &HdrImage, png: &PngSettings) -> Self {
        let (width, height, factor) = fit(image.width, image.height);
        let encoder = Srgb8Encoder::new(png);
        let mut rgb = Vec::with_capacity((width * height) as usize);
        for ty in 0..height {
            for tx in 0..width {
                let mut sum = [0.0f32; 4];
                let mut count = 0.0;
                for y in ty * factor..((ty + 1) * factor).min(image.height) {
                    for x in tx * factor..((tx + 1) * factor).min(image.width) {
                        let p = image.pixels[(y * image.width + x) as usize];
                        for (s, v) in sum.iter_mut().zip(p) {
                            *s += if v.is_finite() { v } else { 0.0 };
                        }
                        count += 1.0;
                    }
                }
                let alpha = (sum[3] / count).clamp(0.0, 1.0);
                let pixel = std::array::from_fn(|c| {
                    // Colour is premultiplied; straight colour for the display transform.
                    let straight = if alpha > 0.0 {
                        sum[c] / count / alpha
                    } else {
                        0.0
                    };
                    let shown = f32::from(encoder.encode(straight));
                    (shown * alpha + f32::from(BACKDROP[c]) * (1.0 - alpha)).round() as u8
                });
                rgb.push(pixel);
            }
        }
        Thumbnail { width, height, rgb }
    }

    /// From an 8-bit RGBA image (a PNG already on disk), nearest-sampled.
    pub fn from_rgba8(width: u32, height: u32, pixels: &[[u8; 4]]) -> Self {
        let (tw, th, factor) = fit(width, height);
        let mut rgb = Vec::with_capacity((tw * th) as usize);
        for ty in 0..th {
            for tx in 0..tw {
                let x = (tx * factor + factor / 2).min(width.saturating_sub(1));
                let y = (ty * factor + factor / 2).min(height.saturating_sub(1));
                let p = pixels
                    .get(y as usize * width as usize + x as usize)
                    .copied()
                    .unwrap_or([0; 4]);
                let a = f32::from(p[3]) / 255.0;
                rgb.push(std::array::from_fn(|c| {
                    (f32::from(p[c]) * a + f32::from(BACKDROP[c]) * (1.0 - a)).round() as u8
                }));
            }
        }
        Thumbnail {
            width: tw,
            height: th,
            rgb,
        }
    }
}

/// Thumbnail size and the integer downsampling factor that makes the longer side ≤ TILE.
fn fit(width: u32, height: u32) -> (u32, u32, u32) {
    let factor = width.max(height).div_ceil(TILE).max(1);
    ((width / factor).max(1), (height / factor).max(1), factor)
}

/// One tile: its image (None for a failed job, or a skipped one whose file cannot be read back),
/// its label lines ([`label`]) and whether the job failed (its label is red).
pub struct Tile {
    pub image: Option<Thumbnail>,
    pub lines: Vec<String>,
    pub failed: bool,
}

/// A tile's label: `#id` (and `FAILED` for a failed job), then `path = value` for at most
/// [`MAX_LABEL_VALUES`] sweeps and a count of the rest. Lines are cut to the tile's width when
/// drawn.
pub fn label(row: &ManifestRow, columns: &[String]) -> Vec<String> {
    let mut lines = vec![match row.status == STATUS_OK {
        true => format!("#{}", row.job),
        false => format!("#{} FAILED (see manifest)", row.job),
    }];
    lines.extend(
        columns
            .iter()
            .zip(&row.values)
            .take(MAX_LABEL_VALUES)
            .map(|(path, value)| format!("{} = {value}", short_path(path))),
    );
    if columns.len() > MAX_LABEL_VALUES {
        lines.push(format!(
            "+{} more values (see manifest)",
            columns.len() - MAX_LABEL_VALUES
        ));
    }
    lines
}

/// `object.0.material.r` → `0.material.r`: enough to tell sweeps apart on a 192-pixel tile.
fn short_path(path: &str) -> &str {
    path.strip_prefix("object.").unwrap_or(path)
}

/// Which of a run's jobs get a tile, and where: the job at place `p` of the run (0, 1, … in the
/// order the run takes them) is shown if `p` is a multiple of `stride`, in tile `p / stride`.
#[derive(Clone, Debug)]
pub struct SheetLayout {
    jobs: usize,
    stride: usize,
    columns: u32,
    rows: u32,
    label_lines: u32,
}

impl SheetLayout {
    /// The layout for a run of `jobs` jobs with `sweeps` swept values: tiles in rows of ⌈√n⌉.
    pub fn new(jobs: usize, sweeps: usize) -> Self {
        let stride = jobs.div_ceil(MAX_SHEET_TILES).max(1);
        let tiles = jobs.div_ceil(stride).max(1);
        let columns = (1..=tiles).find(|c| c * c >= tiles).unwrap_or(tiles);
        let label_lines = 1 + sweeps.min(MAX_LABEL_VALUES) + usize::from(sweeps > MAX_LABEL_VALUES);
        // All four are at most MAX_SHEET_TILES or MAX_LABEL_VALUES + 2: u32 holds them.
        SheetLayout {
            jobs,
            stride,
            columns: columns as u32,
            rows: tiles.div_ceil(columns) as u32,
            label_lines: label_lines as u32,
        }
    }

    /// Whether the job at `place` gets a tile (its thumbnail is worth making).
    pub fn shows(&self, place: usize) -> bool {
        place % self.stride == 0
    }

    fn cell(&self) -> (u32, u32) {
        (TILE + GAP, TILE + self.label_lines * LINE_HEIGHT + 2 * GAP)
    }

    /// A line under the tiles when not every job has one.
    fn footer_height(&self) -> u32 {
        if self.stride > 1 {
            LINE_HEIGHT + GAP
        } else {
            0
        }
    }

    /// Width and height for `rows` rows of tiles: at most 3,208 × 5,279 (16 × 16 tiles of 8
    /// label lines and the footer), so neither the pixel count nor its bytes overflow `u32`.
    fn size(&self, rows: u32) -> (u32, u32) {
        let (cell_w, cell_h) = self.cell();
        (
            self.columns * cell_w + GAP,
            rows * cell_h + GAP + self.footer_height(),
        )
    }
}

/// A contact sheet being drawn: tiles are painted in as jobs finish.
pub struct ContactSheet {
    layout: SheetLayout,
    width: u32,
    height: u32,
    /// RGB8, rows top first.
    pixels: Vec<u8>,
    /// Tiles painted, in order; the sheet is cut below the last row that has one.
    painted: usize,
}

impl ContactSheet {
    /// A white sheet of `layout`'s full size.
    pub fn new(layout: SheetLayout) -> Self {
        let (width, height) = layout.size(layout.rows);
        ContactSheet {
            pixels: vec![255; width as usize * height as usize * 3],
            layout,
            width,
            height,
            painted: 0,
        }
    }

    /// Paints the tile of the job at `place`, if the layout shows it (tiles come in place
    /// order); the tile is dropped after.
    pub fn add(&mut self, place: usize, tile: Tile) -> Result<()> {
        if !self.layout.shows(place) {
            return Ok(());
        }
        let k = place / self.layout.stride;
        let columns = self.layout.columns as usize;
        let (cell_w, cell_h) = self.layout.cell();
        let x0 = GAP + (k % columns) as u32 * cell_w;
        let y0 = GAP + (k / columns).min(self.layout.rows as usize) as u32 * cell_h;
        self.painted = k + 1;
        if let Some(image) = &tile.image {
            self.paint(x0, y0, image);
        }
        let text_top = y0 + tile.image.as_ref().map_or(TILE, |i| i.height.min(TILE)) + 4;
        let color = if tile.failed { RED } else { BLACK };
        let lines = tile
            .lines
            .iter()
            .take(self.layout.label_lines as usize)
            .zip(0..)
            .map(|(text, line)| {
                let y = text_top + line * LINE_HEIGHT;
                Ok((fit_text(text, TILE + GAP / 2)?, x0 as i32, y as i32))
            })
            .collect::<Result<Vec<_>>>()?;
        self.draw_text(&lines, color)
    }

    /// Copies `image` (at most TILE × TILE of it) into the sheet at (x0, y0).
    fn paint(&mut self, x0: u32, y0: u32, image: &Thumbnail) {
        let width = self.width as usize;
        for y in 0..image.height.min(TILE) as usize {
            for x in 0..image.width.min(TILE) as usize {
                let Some(rgb) = image.rgb.get(y * image.width as usize + x) else {
                    return;
                };
                let at = ((y0 as usize + y) * width + x0 as usize + x) * 3;
                if let Some(pixel) = self.pixels.get_mut(at..at + 3) {
                    pixel.copy_from_slice(rgb);
                }
            }
        }
    }

    /// Draws each (text, x, y) through plotters. A panic in it (it asserted on the buffer size
    /// once) becomes this sheet's error instead of ending the batch.
    fn draw_text(&mut self, lines: &[(String, i32, i32)], color: RGBColor) -> Result<()> {
        ensure_font()?;
        let size = (self.width, self.height);
        let pixels = &mut self.pixels;
        let drawn = catch_unwind(AssertUnwindSafe(|| {
            let backend = BitMapBackend::<RGBPixel>::with_buffer_and_format(pixels, size)
                .map_err(|e| e.to_string())?;
            let root = backend.into_drawing_area();
            let style = TextStyle::from((FONT_FAMILY, FONT_SIZE).into_font()).color(&color);
            for (text, x, y) in lines {
                root.draw_text(text, &style, (*x, *y))
                    .map_err(|e| e.to_string())?;
            }
            root.present().map_err(|e| e.to_string())
        }));
        match drawn {
            Ok(Ok(())) => Ok(()),
            Ok(Err(message)) => Err(failed(message)),
            Err(_) => Err(failed("drawing its text panicked; please report".into())),
        }
    }

    /// The sheet as PNG bytes, cut below the last row of tiles painted (a cancelled run's
    /// sheet shows what finished), with the footer when not every job has a tile.
    pub fn finish(mut self) -> Result<Vec<u8>> {
        let columns = self.layout.columns as usize;
        let rows = self.painted.div_ceil(columns).max(1) as u32;
        let (width, height) = self.layout.size(rows.min(self.layout.rows));
        self.pixels.truncate(width as usize * height as usize * 3);
        self.height = height;
        if self.layout.stride > 1 {
            let note = format!(
                "{} of {} jobs shown (one in {}); the manifest lists every job",
                self.painted, self.layout.jobs, self.layout.stride
            );
            let y = height - GAP - LINE_HEIGHT;
            self.draw_text(&[(note, GAP as i32, y as i32)], BLACK)?;
        }
        let mut png = Vec::new();
        image::ImageEncoder::write_image(
            image::codecs::png::PngEncoder::new_with_quality(
                &mut png,
                // Mostly white: fast deflate is near the best here, at a fraction of its time.
                image::codecs::png::CompressionType::Fast,
                image::codecs::png::FilterType::Adaptive,
            ),
            &self.pixels,
            width,
            height,
            image::ExtendedColorType::Rgb8,
        )
        .map_err(|e| failed(e.to_string()))?;
        Ok(png)
    }
}

/// `text`, cut with `…` to fit in `width` pixels (binary search on the characters kept).
fn fit_text(text: &str, width: u32) -> Result<String> {
    // Before anything is measured: a font not yet registered measures nothing, and every line
    // of the first tile was cut to `…`.
    ensure_font()?;
    let font = (FONT_FAMILY, FONT_SIZE).into_font();
    let fits = |s: &str| font.box_size(s).is_ok_and(|(w, _)| w <= width);
    let chars: Vec<char> = text.chars().take(MAX_LABEL_CHARS).collect();
    let whole: String = chars.iter().collect();
    if chars.len() == text.chars().count() && fits(&whole) {
        return Ok(whole);
    }
    let cut = |n: usize| chars[..n].iter().collect::<String>() + "…";
    let (mut keep, mut over) = (0, chars.len());
    while keep + 1 < over {
        let mid = (keep + over) / 2;
        if fits(&cut(mid)) {
            keep = mid;
        } else {
            over = mid;
        }
    }
    Ok(cut(keep))
}

fn failed(message: String) -> Error {
    Error::Write {
        path: "contact_sheet.png".into(),
        message,
    }
}

/// The embedded font, registered once for every plot and sheet (`output::text`), its error
/// named as the sheet's.
fn ensure_font() -> Result<()> {
    crate::output::text::ensure_font().map_err(|e| failed(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thumbnail_of_uniform_grey_keeps_its_srgb_value() {
        // Radiance 0.2140 with no tone curve → sRGB 0.5 → 128 (IEC 61966-2-1: 0.5 encodes 0.2140).
        let mut image = HdrImage::new(400, 200);
        image.pixels.fill([0.214, 0.214, 0.214, 1.0]);
        let png = PngSettings {
            exposure_ev: 0.0,
            tone_curve: crate::output::ToneCurve::None,
        };
        let t = Thumbnail::from_hdr(&image, &png);
        assert_eq!((t.width, t.height), (133, 66)); // factor ⌈400/192⌉ = 3
        assert!(t
            .rgb
            .iter()
            .all(|p| p.iter().all(|&c| (127..=128).contains(&c))));
    }

    fn red_tile(lines: Vec<String>) -> Tile {
        Tile {
            image: Some(Thumbnail {
                width: 10,
                height: 10,
                rgb: vec![[255, 0, 0]; 100],
            }),
            lines,
            failed: false,
        }
    }

    fn decode(png: &[u8]) -> (u32, u32, Vec<[u8; 4]>) {
        crate::output::png::decode_png_rgba8(png).unwrap()
    }

    #[test]
    fn sheet_has_a_cell_per_tile() {
        let mut sheet = ContactSheet::new(SheetLayout::new(3, 2));
        for place in 0..3 {
            let lines = vec![format!("#{place}"), "r = 1".into(), "orbit = 45".into()];
            sheet.add(place, red_tile(lines)).unwrap();
        }
        let (w, h, px) = decode(&sheet.finish().unwrap());
        // 3 tiles → 2 columns, 2 rows; labels of 3 lines (id and two values).
        assert_eq!(w, 2 * (TILE + GAP) + GAP);
        assert_eq!(h, 2 * (TILE + 3 * LINE_HEIGHT + 2 * GAP) + GAP);
        assert_eq!(px[(GAP * w + GAP) as usize], [255, 0, 0, 255]);
    }

    /// Any number of jobs and sweeps gives a sheet of bounded size: the 4,300 jobs with 131
    /// sweeps that panicked (the label's height made the byte count wrap `u32`), a million jobs.
    #[test]
    fn the_sheet_is_bounded_whatever_the_batch() {
        let (max_w, max_h) = (3_208, 5_279);
        for (jobs, sweeps) in [(4_300, 131), (1_000_000, 1), (30_000, 1), (257, 40), (0, 0)] {
            let layout = SheetLayout::new(jobs, sweeps);
            let (w, h) = layout.size(layout.rows);
            assert!(w <= max_w && h <= max_h, "{jobs} jobs: {w} × {h}");
            let shown = (0..jobs).filter(|&p| layout.shows(p)).count();
            assert!(shown <= MAX_SHEET_TILES, "{jobs} jobs: {shown} tiles");
        }
        // The bound itself: 16 × 16 tiles of 1 + 6 + 1 label lines and the footer.
        let layout = SheetLayout::new(1_000_000, 131);
        assert_eq!(layout.size(layout.rows), (max_w, max_h));
    }

    /// 4,300 jobs of 131 sweeps: one job in 17 gets a tile, labels are cut to 8 lines and to the
    /// tile's width, and the footer says how many are shown.
    #[test]
    fn many_jobs_make_a_sampled_sheet_with_a_footer() {
        let columns: Vec<String> = (0..131).map(|k| format!("object.{k}.material.m")).collect();
        let layout = SheetLayout::new(4_300, columns.len());
        let mut sheet = ContactSheet::new(layout.clone());
        for place in (0..4_300).filter(|&p| layout.shows(p)) {
            let row = ManifestRow {
                job: place,
                values: vec!["[0.05, 0.05, \"a long string value\"]".into(); 131],
                output: String::new(),
                scene_hash: String::new(),
                status: "failed: r = 100 is outside [1, 5.63]".into(),
            };
            let tile = Tile {
                image: None,
                lines: label(&row, &columns),
                failed: true,
            };
            assert_eq!(tile.lines.len(), 8);
            sheet.add(place, tile).unwrap();
        }
        let (w, h, _) = decode(&sheet.finish().unwrap());
        // ⌈4300 / 256⌉ = 17: 253 tiles, 16 columns × 16 rows, 8 label lines, the footer.
        let cell_h = TILE + 8 * LINE_HEIGHT + 2 * GAP;
        assert_eq!(
            (w, h),
            (16 * 200 + GAP, 16 * cell_h + GAP + LINE_HEIGHT + GAP)
        );
        assert!(fit_text(&"x".repeat(10_000), TILE).unwrap().ends_with('…'));
    }

    /// Lines that fit are kept whole, also when nothing was drawn yet (the first tile's lines
    /// were all `…`: the font was registered only when the first text was drawn).
    #[test]
    fn short_label_lines_are_kept_whole() {
        assert_eq!(fit_text("#0", TILE).unwrap(), "#0");
        assert_eq!(
            fit_text("0.material.r = 1", TILE).unwrap(),
            "0.material.r = 1"
        );
    }

    /// A cancelled run's sheet ends below its last tile.
    #[test]
    fn a_sheet_is_cut_below_its_last_tile() {
        let mut sheet = ContactSheet::new(SheetLayout::new(100, 0));
        for place in 0..12 {
            sheet
                .add(place, red_tile(vec![format!("#{place}")]))
                .unwrap();
        }
        let (w, h, _) = decode(&sheet.finish().unwrap());
        // 10 columns: 12 tiles fill 2 rows of 1 label line.
        assert_eq!(
            (w, h),
            (10 * 200 + GAP, 2 * (TILE + LINE_HEIGHT + 2 * GAP) + GAP)
        );
    }
}
