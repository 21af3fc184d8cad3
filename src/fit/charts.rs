//! The report's Cartesian figures: the Beckmann lobe and the m search (paper Fig. 4), the Fresnel
//! table (Fig. 5), f(N·V) (Fig. 6) and g(r) (Fig. 8). Split from [`super::plots`], which owns the
//! figure list and the polar figures; these are more methods of its `Context`.

use plotters::prelude::*;

use super::data::luminance;
use super::diffuse::eval_law;
use super::estimate::FittedRow;
use super::plots::{sign, specular_share, Context};
use super::polar::{font, Area, PlotResult, CHANNEL_COLOURS, PALETTE};
use crate::model::brdf::beckmann_d;
use crate::model::{FresnelTable, LacquerMaterial};

impl Context<'_> {
    /// Fig. 4: D measured (specular / (F·G/(4·nv·nl))) against the half-vector's tilt, with the
    /// fitted Beckmann D; and J(m) over the search grid.
    pub(super) fn beckmann(&self, area: &Area) -> PlotResult {
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
    pub(super) fn fresnel(&self, area: &Area) -> PlotResult {
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
    pub(super) fn view_law(&self, area: &Area) -> PlotResult {
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
    pub(super) fn lacquer_law(&self, area: &Area) -> PlotResult {
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
