//! The report's figures, after the paper's: polar plots of measured vs fitted reflectance
//! (Fig. 1 total, Fig. 2 separated diffuse, Fig. 3 separated specular), the Beckmann lobe and
//! the m search (Fig. 4), the Fresnel table (Fig. 5), f(N·V) (Fig. 6) and g(r) (Fig. 8).
//!
//! Polar and lobe plots show luminance Y (Rec. 709) so that a coloured board reads as one curve;
//! the Fresnel plot shows R, G, B. Owns the figure list, their shared context and the polar
//! figures; the Cartesian ones are in [`super::charts`], the drawing plumbing in
//! [`super::polar`].

use glam::DVec3;
use plotters::prelude::*;

use super::data::{in_plane_theta_o, luminance, Measurements};
use super::diffuse::eval_law;
use super::estimate::{FitResult, FittedRow};
use super::polar::PALETTE;
use super::polar::{
    font, legend, polar_panel, render_png, Area, PlotResult, PolarSeries, RadialScale,
};
use crate::model::brdf::{lacquer_brdf, view_dependent_diffuse, BrdfParams};
use crate::Result;

/// Every figure: its file name, its size in pixels and what it draws.
const FIGURES: [(&str, (u32, u32), Figure); 7] = [
    ("fig1_polar_total.png", (1200, 760), Figure::Total),
    ("fig2_polar_diffuse.png", (800, 560), Figure::Diffuse),
    ("fig3_polar_specular.png", (1200, 760), Figure::Specular),
    ("fig4_beckmann.png", (1200, 500), Figure::Beckmann),
    ("fig5_fresnel.png", (1200, 500), Figure::Fresnel),
    ("fig6_f_nv.png", (800, 560), Figure::ViewLaw),
    ("fig8_g_r.png", (800, 560), Figure::LacquerLaw),
];

/// The figures' file names, in the order [`render_all`] returns them.
pub fn figure_names() -> impl Iterator<Item = &'static str> {
    FIGURES.iter().map(|(name, _, _)| *name)
}

/// Every figure as (file name, PNG bytes).
pub fn render_all(data: &Measurements, fit: &FitResult) -> Result<Vec<(String, Vec<u8>)>> {
    let context = Context::new(data, fit)?;
    let mut figures = Vec::new();
    for (name, size, draw) in FIGURES {
        let png = render_png(name, size, |area| context.draw(draw, area))?;
        figures.push((name.to_string(), png));
    }
    Ok(figures)
}

#[derive(Clone, Copy)]
enum Figure {
    Total,
    Diffuse,
    Specular,
    Beckmann,
    Fresnel,
    ViewLaw,
    LacquerLaw,
}

/// What every figure needs: the data, the fit and the per-board BRDF parameters.
pub(super) struct Context<'a> {
    pub(super) data: &'a Measurements,
    pub(super) fit: &'a FitResult,
    params: Vec<BrdfParams>,
    /// The least-lacquer board (the polar figures show it).
    reference_board: usize,
}

impl<'a> Context<'a> {
    fn new(data: &'a Measurements, fit: &'a FitResult) -> Result<Self> {
        let base = fit.material.brdf_params()?;
        let params = data
            .samples
            .iter()
            .map(|s| BrdfParams {
                lacquer_g: eval_law(fit.material.lacquer_law, s.lacquer_ratio),
                ..base
            })
            .collect();
        let reference_board = (0..data.samples.len())
            .min_by(|&a, &b| {
                let r = |s: usize| data.samples[s].lacquer_ratio;
                r(a).total_cmp(&r(b))
            })
            .unwrap_or(0);
        Ok(Context {
            data,
            fit,
            params,
            reference_board,
        })
    }

    fn draw(&self, figure: Figure, area: &Area) -> PlotResult {
        match figure {
            Figure::Total => self.polar_by_incidence(area, false),
            Figure::Diffuse => self.polar_diffuse(area),
            Figure::Specular => self.polar_by_incidence(area, true),
            Figure::Beckmann => self.beckmann(area),
            Figure::Fresnel => self.fresnel(area),
            Figure::ViewLaw => self.view_law(area),
            Figure::LacquerLaw => self.lacquer_law(area),
        }
    }

    /// In-plane rows of `board`: (θ_i rounded to 0.1°, signed θ_o, row).
    fn in_plane(&self, board: usize) -> Vec<(f64, f64, &'a FittedRow)> {
        self.fit
            .rows
            .iter()
            .filter(|r| self.data.rows[r.index].sample == board)
            .filter_map(|r| {
                let m = &self.data.rows[r.index];
                let theta_o = in_plane_theta_o(m.light, m.view, 0.5)?;
                let theta_i = (m.light.z.acos().to_degrees() * 10.0).round() / 10.0;
                Some((theta_i, theta_o, r))
            })
            .collect()
    }

    /// The model's (diffuse, specular) luminance for `board` at θ_i and signed in-plane θ_o.
    fn model_in_plane(&self, board: usize, theta_i: f64, theta_o: f64) -> (f64, f64) {
        let light = super::data::light_direction(theta_i);
        let view = super::data::view_direction(theta_o, 0.0);
        let p = &self.params[board];
        let total = lacquer_brdf(p, &self.fit.fresnel, DVec3::Z, view, light);
        let diffuse = view_dependent_diffuse(p, view.z);
        let pi = std::f64::consts::PI;
        let d = luminance(diffuse) * pi;
        (d, luminance(total) * pi - d)
    }

    /// Figs. 1 and 3: one panel per incidence angle (up to six), measured points and the fitted
    /// curve, reflectance in decades (the specular peak is hundreds of times the diffuse level).
    fn polar_by_incidence(&self, area: &Area, specular_only: bool) -> PlotResult {
        let board = self.reference_board;
        let rows = self.in_plane(board);
        let mut incidences: Vec<f64> = rows.iter().map(|r| r.0).collect();
        incidences.sort_by(f64::total_cmp);
        incidences.dedup();
        let chosen = pick_evenly(&incidences, 6);
        let value = |r: &FittedRow| {
            luminance(if specular_only {
                r.separated_specular
            } else {
                r.measured
            })
        };
        // Where the model has almost no specular part, the separated specular part is only the
        // diffuse part's noise: not shown.
        let shown = |r: &FittedRow| !specular_only || specular_share(r) > 0.01;
        let measured: Vec<Vec<(f64, f64)>> = chosen
            .iter()
            .map(|&ti| {
                rows.iter()
                    .filter(|r| r.0 == ti && shown(r.2))
                    .map(|r| (r.1, value(r.2)))
                    .filter(|p| p.1 > 0.0)
                    .collect()
            })
            .collect();
        // Curves over the measured span only: towards the horizon the model falls to 0 and would
        // stretch the decades.
        let span = |k: usize| {
            let angles = measured[k].iter().map(|p| p.0);
            let lo = angles.clone().fold(f64::INFINITY, f64::min);
            (lo, angles.fold(f64::NEG_INFINITY, f64::max))
        };
        let curves: Vec<Vec<(f64, f64)>> = chosen
            .iter()
            .enumerate()
            .map(|(k, &ti)| {
                let (lo, hi) = span(k);
                (0..=720)
                    .map(|q| {
                        let to = lo + (hi - lo) * f64::from(q) / 720.0;
                        let (d, s) = self.model_in_plane(board, ti, to);
                        (to, if specular_only { s } else { d + s })
                    })
                    .collect()
            })
            .collect();
        // Each panel its own decades: the peak grows a thousandfold from θ_i = 0 to 80°.
        let scale = |k: usize| {
            let all = measured[k].iter().chain(&curves[k]).map(|p| p.1);
            let max = all.clone().fold(0.0, f64::max);
            let min = all.filter(|&v| v > 0.0).fold(f64::INFINITY, f64::min);
            RadialScale::decades(min, max, 5.0)
        };
        let what = if specular_only {
            "Separated specular reflectance (paper Fig. 3)"
        } else {
            "Reflectance factor π·f_r (paper Fig. 1)"
        };
        let title = format!(
            "{what}, luminance, board `{}` — points measured, lines fitted (m = {:.4})",
            self.data.samples[board].name, self.fit.material.beckmann_m
        );
        let area = area.titled(&title, font(18))?;
        let panels = area.split_evenly((2, 3));
        for (k, &ti) in chosen.iter().enumerate() {
            polar_panel(
                &panels[k],
                &format!("θ_i = {ti}°"),
                scale(k),
                Some(ti),
                &[
                    PolarSeries {
                        points: measured[k].clone(),
                        colour: PALETTE[0],
                        markers: true,
                    },
                    PolarSeries {
                        points: curves[k].clone(),
                        colour: PALETTE[1],
                        markers: false,
                    },
                ],
            )?;
        }
        Ok(())
    }

    /// Fig. 2: the separated diffuse part of every board (all incidences), with the fitted
    /// k_d·g(r)·f(N·V); linear radius.
    fn polar_diffuse(&self, area: &Area) -> PlotResult {
        let mut series = Vec::new();
        let mut max: f64 = 0.0;
        for board in 0..self.data.samples.len() {
            let colour = PALETTE[board % PALETTE.len()];
            let points: Vec<(f64, f64)> = self
                .in_plane(board)
                .iter()
                .filter(|r| specular_share(r.2) < 0.1)
                .map(|r| (r.1, luminance(r.2.separated_diffuse)))
                .collect();
            let curve: Vec<(f64, f64)> = (-89..=89)
                .map(|d| {
                    let to = f64::from(d);
                    (to, self.model_in_plane(board, 0.0, to).0)
                })
                .collect();
            max = points.iter().chain(&curve).map(|p| p.1).fold(max, f64::max);
            series.push(PolarSeries {
                points,
                colour,
                markers: true,
            });
            series.push(PolarSeries {
                points: curve,
                colour: RGBColor(0, 0, 0),
                markers: false,
            });
        }
        let entries: Vec<(String, RGBColor)> = self
            .data
            .samples
            .iter()
            .enumerate()
            .map(|(b, s)| {
                let label = format!("{} (r = {})", s.name, s.lacquer_ratio);
                (label, PALETTE[b % PALETTE.len()])
            })
            .collect();
        let title =
            "Separated diffuse part (paper Fig. 2), luminance: points measured, black lines fitted";
        polar_panel(
            area,
            title,
            RadialScale::Linear { max: max * 1.05 },
            None,
            &series,
        )?;
        legend(area, &entries)
    }
}

/// "+" or "−" for a coefficient printed by its magnitude.
pub(super) fn sign(v: f64) -> char {
    if v < 0.0 {
        '−'
    } else {
        '+'
    }
}

/// The specular share of a row's model (luminance).
pub(super) fn specular_share(row: &FittedRow) -> f64 {
    let (d, s) = (luminance(row.model_diffuse), luminance(row.model_specular));
    if d + s > 0.0 {
        s / (d + s)
    } else {
        0.0
    }
}

/// Up to `n` values spread evenly over a sorted list (all of them if there are fewer).
fn pick_evenly(values: &[f64], n: usize) -> Vec<f64> {
    if values.len() <= n {
        return values.to_vec();
    }
    (0..n)
        .map(|i| values[(i * (values.len() - 1) + (n - 1) / 2) / (n - 1)])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pick_evenly_keeps_the_ends() {
        let v: Vec<f64> = (0..17).map(|i| f64::from(i) * 5.0).collect();
        let picked = pick_evenly(&v, 6);
        // Indices round(i·16/5) = 0, 3, 6, 10, 13, 16 → 0, 15, 30, 50, 65, 80 degrees.
        assert_eq!(picked, vec![0.0, 15.0, 30.0, 50.0, 65.0, 80.0]);
        assert_eq!(pick_evenly(&v[..3], 6), vec![0.0, 5.0, 10.0]);
    }
}
