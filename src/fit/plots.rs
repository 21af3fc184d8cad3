//! The report's figures, after the paper's: polar plots of measured vs fitted reflectance
//! (Fig. 1 total, Fig. 2 separated diffuse, Fig. 3 separated specular), the Beckmann lobe and
//! the m search (Fig. 4), the Fresnel table (Fig. 5), f(N·V) (Fig. 6) and g(r) (Fig. 8).
//!
//! Polar and lobe plots show luminance Y (Rec. 709) so that a coloured board reads as one curve;
//! the Fresnel plot shows R, G, B. Owns what each figure shows; drawing is [`super::polar`].

use glam::DVec3;
use plotters::prelude::*;

use super::data::{in_plane_theta_o, luminance, Measurements};
use super::diffuse::eval_law;
use super::estimate::{FitResult, FittedRow};
use super::polar::{
    font, legend, polar_panel, render_png, Area, PlotResult, PolarSeries, RadialScale,
};
use super::polar::{CHANNEL_COLOURS, PALETTE};
use crate::model::brdf::{beckmann_d, lacquer_brdf, view_dependent_diffuse, BrdfParams};
use crate::model::{FresnelTable, LacquerMaterial};
use crate::Result;

/// Every figure as (file name, PNG bytes).
pub fn render_all(data: &Measurements, fit: &FitResult) -> Result<Vec<(String, Vec<u8>)>> {
    let context = Context::new(data, fit)?;
    let mut figures = Vec::new();
    for (name, size, draw) in [
        ("fig1_polar_total.png", (1200, 760), Figure::Total),
        ("fig2_polar_diffuse.png", (800, 560), Figure::Diffuse),
        ("fig3_polar_specular.png", (1200, 760), Figure::Specular),
        ("fig4_beckmann.png", (1200, 500), Figure::Beckmann),
        ("fig5_fresnel.png", (1200, 500), Figure::Fresnel),
        ("fig6_f_nv.png", (800, 560), Figure::ViewLaw),
        ("fig8_g_r.png", (800, 560), Figure::LacquerLaw),
    ] {
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
struct Context<'a> {
    data: &'a Measurements,
    fit: &'a FitResult,
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

    /// Fig. 4: D measured (specular / (F·G/(4·nv·nl))) against the half-vector's tilt, with the
    /// fitted Beckmann D; and J(m) over the search grid.
    fn beckmann(&self, area: &Area) -> PlotResult {
        let (left, right) = area.split_horizontally(area.dim_in_pixel().0 / 2);
        let m = self.fit.material.beckmann_m;
        let points: Vec<(f64, f64)> = self
            .fit
            .rows
            .iter()
            .filter(|r| specular_share(r) > 0.5)
            .filter_map(|r| {
                let f = luminance(self.fit.fresnel.eval(r.geometry.fresnel_deg));
                let d = luminance(r.separated_specular) / (f * r.geometry.spec_geometry);
                (d > 0.0).then_some((r.geometry.tilt_deg, d))
            })
            .collect();
        let max_tilt = points.iter().map(|p| p.0).fold(1.0, f64::max);
        let top = points
            .iter()
            .map(|p| p.1)
            .fold(beckmann_d(1.0, m), f64::max);
        let curve: Vec<(f64, f64)> = (0..=400)
            .map(|i| {
                let a = max_tilt * f64::from(i) / 400.0;
                (a, beckmann_d(a.to_radians().cos(), m))
            })
            .filter(|p| p.1 >= top * 1e-4)
            .collect();
        let mut chart = ChartBuilder::on(&left)
            .caption(format!("Beckmann D, m = {m:.4} (paper Fig. 4)"), font(18))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..max_tilt, (top * 1e-4..top * 2.0).log_scale())?;
        chart
            .configure_mesh()
            .x_desc("half-vector tilt α from the normal [°]")
            .y_desc("D [1/sr]")
            .label_style(font(12))
            .axis_desc_style(font(14))
            .draw()?;
        chart
            .draw_series(
                points
                    .iter()
                    .map(|&p| Circle::new(p, 2, PALETTE[0].filled())),
            )?
            .label("measured: separated specular / (π·F·G/(4·N·V·N·L))")
            .legend(|(x, y)| Circle::new((x + 10, y), 3, PALETTE[0].filled()));
        chart
            .draw_series(LineSeries::new(curve, PALETTE[1].stroke_width(2)))?
            .label("fitted Beckmann D")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], PALETTE[1].stroke_width(2)));
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .label_font(font(12))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()?;

        let grid: Vec<(f64, f64)> = self
            .fit
            .beckmann_grid
            .iter()
            .copied()
            .filter(|p| p.1.is_finite() && p.1 > 0.0)
            .collect();
        let (jmin, jmax) = grid.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), p| {
            (lo.min(p.1), hi.max(p.1))
        });
        let (mlo, mhi) = (
            grid.first().map_or(0.005, |p| p.0),
            grid.last().map_or(1.0, |p| p.0),
        );
        let mut chart = ChartBuilder::on(&right)
            .caption("Search for m: residual J(m)", font(18))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(
                (mlo..mhi).log_scale(),
                (jmin.max(1e-300) * 0.5..jmax.max(1e-300) * 2.0).log_scale(),
            )?;
        chart
            .configure_mesh()
            .x_desc("Beckmann m")
            .y_desc("weighted squared residual J")
            .label_style(font(12))
            .axis_desc_style(font(14))
            .draw()?;
        chart.draw_series(LineSeries::new(grid.clone(), PALETTE[0].stroke_width(2)))?;
        chart.draw_series(grid.iter().map(|&p| Circle::new(p, 3, PALETTE[0].filled())))?;
        chart.draw_series(LineSeries::new(
            [(m, jmin.max(1e-300) * 0.5), (m, jmax.max(1e-300) * 2.0)],
            PALETTE[1].stroke_width(2),
        ))?;
        Ok(())
    }

    /// Fig. 5: the fitted table per channel (solid where the data reach, dashed where it was
    /// interpolated) and the default dielectric table for comparison; the right panel enlarges
    /// 0–60°, where the channels differ (the paper's rise of blue) by only a few thousandths.
    fn fresnel(&self, area: &Area) -> PlotResult {
        let (left, right) = area.split_horizontally(area.dim_in_pixel().0 / 2);
        self.fresnel_panel(
            &left,
            90.0,
            "Fresnel table F(θ), θ = acos(V·H) (paper Fig. 5)",
        )?;
        self.fresnel_panel(&right, 60.0, "detail, 0–60°")
    }

    fn fresnel_panel(&self, area: &Area, max_deg: f64, title: &str) -> PlotResult {
        let table = &self.fit.fresnel;
        let default = FresnelTable::dielectric(
            LacquerMaterial::default().ior_a,
            LacquerMaterial::default().ior_b,
        )?;
        let in_range = |a: f64| a <= max_deg;
        let values = table
            .angles_deg()
            .iter()
            .zip(table.rgb())
            .filter(|(&a, _)| in_range(a))
            .flat_map(|(_, v)| *v);
        let (lo, hi) = values.fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
        let pad = 0.1 * (hi - lo).max(1e-3);
        let bottom = if max_deg >= 90.0 {
            0.0
        } else {
            (lo - pad).max(0.0)
        };
        let mut chart = ChartBuilder::on(area)
            .caption(title, font(18))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..max_deg, bottom..hi + pad)?;
        chart
            .configure_mesh()
            .x_desc("θ [°]")
            .y_desc("F (linear RGB)")
            .label_style(font(12))
            .axis_desc_style(font(14))
            .draw()?;
        let measured = |k: usize| self.fit.fresnel_measured(k);
        let grey = RGBColor(120, 120, 120);
        let dielectric: Vec<(f64, f64)> = default
            .angles_deg()
            .iter()
            .zip(default.rgb())
            .filter(|(&a, _)| in_range(a))
            .map(|(&a, v)| (a, luminance(*v)))
            .collect();
        chart
            .draw_series(DashedLineSeries::new(
                dielectric,
                3,
                4,
                grey.stroke_width(1),
            ))?
            .label("default dielectric (n = 1.5 + 0.0045/λ²), luminance")
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], grey));
        for (c, name) in ["R", "G", "B"].iter().enumerate() {
            let colour = CHANNEL_COLOURS[c];
            let all: Vec<(f64, f64)> = table
                .angles_deg()
                .iter()
                .zip(table.rgb())
                .filter(|(&a, _)| in_range(a))
                .map(|(&a, v)| (a, v[c]))
                .collect();
            chart.draw_series(DashedLineSeries::new(
                all.clone(),
                6,
                4,
                colour.stroke_width(1),
            ))?;
            let solid: Vec<(f64, f64)> = all
                .iter()
                .enumerate()
                .filter(|(k, _)| measured(*k))
                .map(|(_, p)| *p)
                .collect();
            chart
                .draw_series(LineSeries::new(solid, colour.stroke_width(2)))?
                .label(format!("{name} fitted (dashed: interpolated)"))
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 20, y)], colour.stroke_width(2))
                });
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .label_font(font(12))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()?;
        Ok(())
    }

    /// Fig. 6: f(N·V) measured — each board's separated diffuse luminance divided by its own
    /// albedo at N·V = 1, times f(1) — against the fitted a + b·N·V.
    fn view_law(&self, area: &Area) -> PlotResult {
        let (a, b) = (self.fit.material.diffuse_a, self.fit.material.diffuse_b);
        let f1 = self.fit.normalisation.f_at_normal;
        let mut chart = ChartBuilder::on(area)
            .caption(
                format!(
                    "f(N·V) = {a:.4} {} {:.4}·N·V (paper Fig. 6)",
                    sign(b),
                    b.abs()
                ),
                font(18),
            )
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..1.0, 0.0..(a + b).max(a).max(0.1) * 1.25)?;
        chart
            .configure_mesh()
            .x_desc("N·V")
            .y_desc("f")
            .label_style(font(12))
            .axis_desc_style(font(14))
            .draw()?;
        for (board, sample) in self.data.samples.iter().enumerate() {
            let k = luminance(self.fit.diffuse.board_albedo[board]);
            let colour = PALETTE[board % PALETTE.len()];
            let rows: Vec<&FittedRow> = self
                .fit
                .rows
                .iter()
                .filter(|r| self.data.rows[r.index].sample == board && specular_share(r) < 0.01)
                .collect();
            // At most ~1500 points per board keep the figure readable.
            let step = (rows.len() / 1500).max(1);
            chart
                .draw_series(rows.iter().step_by(step).map(|r| {
                    let f = luminance(r.separated_diffuse) / k * f1;
                    Circle::new((r.geometry.nv, f), 2, colour.mix(0.6).filled())
                }))?
                .label(format!("{} (r = {})", sample.name, sample.lacquer_ratio))
                .legend(move |(x, y)| Circle::new((x + 10, y), 3, colour.filled()));
        }
        chart
            .draw_series(LineSeries::new(
                [(0.0, a), (1.0, a + b)],
                BLACK.stroke_width(2),
            ))?
            .label("fitted a + b·N·V")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], BLACK.stroke_width(2)));
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .label_font(font(12))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()?;
        Ok(())
    }

    /// Fig. 8: each board's normalised luminance (times the normalisation's g(r_min)) and the
    /// fitted g(r), with the paper's eq. (8) for comparison.
    fn lacquer_law(&self, area: &Area) -> PlotResult {
        let law = self.fit.material.lacquer_law;
        let ratios: Vec<f64> = self.data.samples.iter().map(|s| s.lacquer_ratio).collect();
        let r_min = ratios.iter().copied().fold(f64::INFINITY, f64::min);
        let r_max = ratios.iter().copied().fold(r_min + 1.0, f64::max) + 0.5;
        let g_min = eval_law(self.fit.normalisation.lacquer_law, r_min);
        let points: Vec<(f64, f64)> = ratios
            .iter()
            .zip(&self.fit.diffuse.normalised_luminance)
            .map(|(&r, &y)| (r, y * g_min))
            .collect();
        let curve = |law: [f64; 3]| -> Vec<(f64, f64)> {
            (0..=200)
                .map(|i| {
                    let r = r_min.min(1.0) + (r_max - r_min.min(1.0)) * f64::from(i) / 200.0;
                    (r, eval_law(law, r))
                })
                .collect()
        };
        let paper = LacquerMaterial::default().lacquer_law;
        let top = points
            .iter()
            .chain(&curve(law))
            .map(|p| p.1)
            .fold(eval_law(paper, 1.0), f64::max);
        let [c0, c1, c2] = law;
        let mut chart = ChartBuilder::on(area)
            .caption(
                format!(
                    "g(r) = {c0:.4} {} {:.4}·r {} {:.5}·r² (paper Fig. 8)",
                    sign(c1),
                    c1.abs(),
                    sign(c2),
                    c2.abs()
                ),
                font(18),
            )
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(r_min.min(1.0)..r_max, 0.0..top * 1.15)?;
        chart
            .configure_mesh()
            .x_desc("lacquer ratio r")
            .y_desc("g")
            .label_style(font(12))
            .axis_desc_style(font(14))
            .draw()?;
        chart
            .draw_series(
                points
                    .iter()
                    .map(|&p| Circle::new(p, 5, PALETTE[0].filled())),
            )?
            .label("boards: diffuse luminance / least-lacquer board's × g(r_min)")
            .legend(|(x, y)| Circle::new((x + 10, y), 4, PALETTE[0].filled()));
        chart
            .draw_series(LineSeries::new(curve(law), PALETTE[1].stroke_width(2)))?
            .label(if self.fit.diffuse.lacquer_law_fitted {
                "fitted g(r)"
            } else {
                "g(r) kept (one ratio: not fitted)"
            })
            .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], PALETTE[1].stroke_width(2)));
        let grey = RGBColor(120, 120, 120);
        chart
            .draw_series(DashedLineSeries::new(
                curve(paper),
                6,
                4,
                grey.stroke_width(1),
            ))?
            .label("paper eq. (8)")
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], grey));
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .label_font(font(12))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()?;
        Ok(())
    }
}

/// "+" or "−" for a coefficient printed by its magnitude.
fn sign(v: f64) -> char {
    if v < 0.0 {
        '−'
    } else {
        '+'
    }
}

/// The specular share of a row's model (luminance).
fn specular_share(row: &FittedRow) -> f64 {
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
