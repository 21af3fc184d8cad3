//! The pinhole camera of SPEC §1, shared by the GPU draw and the CPU oracle.
//!
//! Owns the two descriptions of one camera: the primary ray through an image point (what the
//! oracle ray-casts) and the view-projection matrix (what the vertex shader uses). They are
//! written independently from the SPEC formula and a test checks they agree to 1e-6 rad.
//! Does not touch images, meshes or the GPU.

use glam::{DMat4, DVec3, DVec4, Mat4};

use crate::model::limits;
use crate::{Error, Result};

/// A look-at pinhole camera; vertical field of view, aspect = W/H of the image it renders.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub eye: DVec3,
    pub target: DVec3,
    pub up: DVec3,
    pub fov_deg: f64,
}

impl Default for Camera {
    /// Looking down -Z at the unit sphere from 4 units away: with 40° the sphere fills about
    /// 2·asin(1/4)/40° ≈ 72 % of the image height.
    fn default() -> Self {
        Camera {
            eye: DVec3::new(0.0, 0.0, 4.0),
            target: DVec3::ZERO,
            up: DVec3::Y,
            fov_deg: 40.0,
        }
    }
}

/// Below this |forward × up| (sine of the angle between them) the camera's roll is undefined.
const MIN_UP_SINE: f64 = 1e-6;

impl Camera {
    /// Checks the camera can form an orthonormal frame and a finite projection.
    pub fn validate(&self) -> Result<()> {
        let vectors = [("eye", self.eye), ("target", self.target), ("up", self.up)];
        for (name, v) in vectors {
            if let Some(reason) = limits::coordinate_problem(v) {
                return Err(Error::invalid(
                    format!("camera.{name}"),
                    format_vec(v),
                    reason,
                ));
            }
        }
        let view = self.target - self.eye;
        let reach = self.eye.length().max(self.target.length()).max(1.0);
        if view.length() <= limits::MIN_VIEW_DISTANCE * reach {
            return Err(Error::invalid(
                "camera.target",
                format_vec(self.target),
                format!(
                    "the target must differ from the eye by more than {:e} of their distance \
                     from the origin (or 1), or the view direction is f32 rounding; move the \
                     eye or the target",
                    limits::MIN_VIEW_DISTANCE
                ),
            ));
        }
        let sine = match self.up.try_normalize() {
            Some(up) => view.normalize().cross(up).length(),
            None => 0.0,
        };
        if sine < MIN_UP_SINE {
            return Err(Error::invalid(
                "camera.up",
                format_vec(self.up),
                "up must be non-zero and not parallel to the view direction (target - eye); \
                 choose another up vector, e.g. 0,0,1 when looking straight down",
            ));
        }
        if !(self.fov_deg.is_finite()
            && self.fov_deg >= limits::MIN_FOV_DEG
            && self.fov_deg < 180.0)
        {
            return Err(Error::invalid(
                "camera.fov_deg",
                self.fov_deg,
                format!(
                    "the vertical field of view must be in [{}, 180) degrees, e.g. 40",
                    limits::MIN_FOV_DEG
                ),
            ));
        }
        Ok(())
    }

    /// The camera frame in world space: (right = +X_cam, up = +Y_cam, forward = -Z_cam).
    pub fn basis(&self) -> (DVec3, DVec3, DVec3) {
        let forward = (self.target - self.eye).normalize();
        let right = forward.cross(self.up).normalize();
        let up = right.cross(forward);
        (right, up, forward)
    }

    /// Unit world-space direction of the primary ray through the image point (px, py), in pixels
    /// from the top-left corner (pixel (i, j)'s centre is (i+0.5, j+0.5)), using exactly SPEC §1:
    /// x_ndc = (2px/W - 1)·tan(fov/2)·W/H, y_ndc = (1 - 2py/H)·tan(fov/2), camera looks along -Z_cam.
    pub fn primary_ray(&self, px: f64, py: f64, width: u32, height: u32) -> DVec3 {
        let (w, h) = (f64::from(width), f64::from(height));
        let tan_half = (0.5 * self.fov_deg.to_radians()).tan();
        let x_ndc = (2.0 * px / w - 1.0) * tan_half * w / h;
        let y_ndc = (1.0 - 2.0 * py / h) * tan_half;
        let (right, up, forward) = self.basis();
        // Camera-space direction (x_ndc, y_ndc, -1); -Z_cam is `forward`.
        (x_ndc * right + y_ndc * up + forward).normalize()
    }

    /// Right-handed look-at: world → camera space, camera at the origin looking along -Z.
    pub fn view_matrix(&self) -> DMat4 {
        DMat4::look_at_rh(self.eye, self.target, self.up)
    }

    /// Perspective for Vulkan clip space: depth 0 at `near` .. 1 at `far`, and +Y down (the flip
    /// is here, SPEC §1), so a point projected by [`Camera::view_projection`] lands at the pixel
    /// whose primary ray hits it.
    ///
    /// With f = 1/tan(fov/2) and camera-space (x, y, z), z < 0 in front:
    /// clip = (f/aspect·x, -f·y, far/(near-far)·z + near·far/(near-far), -z).
    /// Then ndc_x = x/(-z)·f/aspect, and px = (ndc_x+1)/2·W inverts SPEC §1's x_ndc = x/(-z);
    /// likewise ndc_y = -y/(-z)·f with py = (ndc_y+1)/2·H inverts y_ndc = y/(-z).
    pub fn projection_vulkan(&self, aspect: f64, near: f64, far: f64) -> DMat4 {
        let f = 1.0 / (0.5 * self.fov_deg.to_radians()).tan();
        let depth_scale = far / (near - far);
        DMat4::from_cols(
            DVec4::new(f / aspect, 0.0, 0.0, 0.0),
            DVec4::new(0.0, -f, 0.0, 0.0),
            DVec4::new(0.0, 0.0, depth_scale, -1.0),
            DVec4::new(0.0, 0.0, near * depth_scale, 0.0),
        )
    }

    /// The near and far planes for a scene inside `scene` (a sphere, or a radius about the
    /// origin): tight around the sphere (1 % margin) so the depth buffer's precision is spent on
    /// the scene. When the eye is inside or almost touching the sphere, near falls back to
    /// far·1e-4 — a far/near ratio a 32-bit depth buffer still resolves well.
    pub fn depth_range(&self, scene: impl Into<SceneSphere>) -> (f64, f64) {
        let scene = scene.into();
        let radius = if scene.radius.is_finite() && scene.radius > 0.0 {
            scene.radius
        } else {
            1.0
        };
        let distance = self.eye.distance(scene.center);
        let far = (distance + radius) * 1.01;
        let near = ((distance - radius) * 0.99).max(far * 1e-4);
        (near, far)
    }

    /// f32 view-projection for the vertex shader, near/far from [`Camera::depth_range`].
    /// A zero width or height is treated as 1 so the matrix stays finite.
    pub fn view_projection(&self, width: u32, height: u32, scene: impl Into<SceneSphere>) -> Mat4 {
        let aspect = f64::from(width.max(1)) / f64::from(height.max(1));
        let (near, far) = self.depth_range(scene);
        (self.projection_vulkan(aspect, near, far) * self.view_matrix()).as_mat4()
    }
}

/// A sphere holding every object of a scene, which sets the depth range
/// ([`Camera::depth_range`]). About the scene's own centre: one about the origin put a scene
/// 1e5 from it, seen from 3.6 units, behind the near plane (it drew nothing; found by a probe,
/// 2026-12-06).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneSphere {
    pub center: DVec3,
    pub radius: f64,
}

impl SceneSphere {
    /// The sphere about the centre of the boxes' union, through its corners; None without boxes.
    pub fn around_boxes(boxes: impl IntoIterator<Item = (DVec3, DVec3)>) -> Option<Self> {
        let (min, max) = boxes
            .into_iter()
            .reduce(|(a0, a1), (b0, b1)| (a0.min(b0), a1.max(b1)))?;
        Some(SceneSphere {
            center: 0.5 * (min + max),
            radius: 0.5 * min.distance(max),
        })
    }
}

impl From<f64> for SceneSphere {
    /// A sphere of that radius about the origin.
    fn from(radius: f64) -> Self {
        SceneSphere {
            center: DVec3::ZERO,
            radius,
        }
    }
}

/// A rectangle of pixels: columns `x0..x1`, rows `y0..y1` (row 0 at the top).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelRect {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

impl PixelRect {
    pub fn is_empty(&self) -> bool {
        self.x0 >= self.x1 || self.y0 >= self.y1
    }
}

impl Camera {
    /// Pixels that can hold a sample of anything inside the axis-aligned box `min..max`, for a
    /// `width` × `height` image: the projections of the box's corners, widened by 2 pixels for
    /// rounding, clamped to the image. The whole image when a corner is not in front of the
    /// camera (the box straddles the eye plane, so its projection is unbounded).
    pub fn screen_bounds(
        &self,
        (min, max): (DVec3, DVec3),
        width: u32,
        height: u32,
        scene: impl Into<SceneSphere>,
    ) -> PixelRect {
        let whole = PixelRect {
            x0: 0,
            y0: 0,
            x1: width,
            y1: height,
        };
        let aspect = f64::from(width.max(1)) / f64::from(height.max(1));
        let (near, far) = self.depth_range(scene);
        let view_projection = self.projection_vulkan(aspect, near, far) * self.view_matrix();
        let (mut lo, mut hi) = (glam::DVec2::splat(f64::INFINITY), glam::DVec2::NEG_INFINITY);
        for corner in 0..8 {
            let pick = |bit: u32, a: f64, b: f64| if corner & bit == 0 { a } else { b };
            let point = DVec3::new(
                pick(1, min.x, max.x),
                pick(2, min.y, max.y),
                pick(4, min.z, max.z),
            );
            let clip = view_projection * point.extend(1.0);
            if !(clip.w > 1e-9 && clip.is_finite()) {
                return whole;
            }
            let ndc = clip.truncate().truncate() / clip.w;
            let pixel = (ndc + 1.0) * 0.5 * glam::DVec2::new(f64::from(width), f64::from(height));
            lo = lo.min(pixel);
            hi = hi.max(pixel);
        }
        let clamp = |v: f64, limit: u32| v.clamp(0.0, f64::from(limit)) as u32;
        PixelRect {
            x0: clamp((lo.x - 2.0).floor(), width),
            y0: clamp((lo.y - 2.0).floor(), height),
            x1: clamp((hi.x + 2.0).ceil(), width),
            y1: clamp((hi.y + 2.0).ceil(), height),
        }
    }
}

fn format_vec(v: DVec3) -> String {
    format!("{},{},{}", v.x, v.y, v.z)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec4;

    fn oblique_camera() -> Camera {
        Camera {
            eye: DVec3::new(1.3, 2.1, 3.7),
            target: DVec3::new(0.2, -0.1, 0.3),
            up: DVec3::Y,
            fov_deg: 35.0,
        }
    }

    /// Vulkan NDC → pixel coordinates, as the rasteriser maps them with a full-image viewport.
    fn project_to_pixel(vp: Mat4, point: DVec3, width: u32, height: u32) -> (f64, f64, f64) {
        let clip = vp * Vec4::new(point.x as f32, point.y as f32, point.z as f32, 1.0);
        let ndc = clip.truncate() / clip.w;
        let px = (f64::from(ndc.x) + 1.0) / 2.0 * f64::from(width);
        let py = (f64::from(ndc.y) + 1.0) / 2.0 * f64::from(height);
        (px, py, f64::from(ndc.z))
    }

    #[test]
    fn projection_and_primary_ray_agree() {
        // Tolerance 1e-6 rad: the f32 matrix and f32 point carry ~6e-8 relative error, i.e.
        // ~1e-7 rad at these distances; 1e-6 leaves margin but catches any half-pixel or
        // sign mistake (a pixel here subtends ~1e-3 rad).
        let camera = oblique_camera();
        let (width, height) = (640, 360);
        let vp = camera.view_projection(width, height, 1.5);
        let points = [
            DVec3::new(0.2, -0.1, 0.3),
            DVec3::new(0.9, 0.4, -0.5),
            DVec3::new(-1.0, 0.3, 0.8),
            DVec3::new(0.1, -1.2, -1.1),
        ];
        for point in points {
            // The point as the GPU sees it (f32), so rounding of the input is not counted.
            let point = point.as_vec3().as_dvec3();
            let (px, py, depth) = project_to_pixel(vp, point, width, height);
            assert!((0.0..=1.0).contains(&depth), "depth {depth} outside 0..1");
            let ray = camera.primary_ray(px, py, width, height);
            let towards = (point - camera.eye).normalize();
            let angle = ray.angle_between(towards);
            assert!(angle < 1e-6, "{point}: pixel ({px}, {py}), angle {angle}");
        }
    }

    #[test]
    fn point_above_target_lands_in_upper_half() {
        let camera = Camera::default();
        let vp = camera.view_projection(200, 100, 1.0);
        let (px, py, _) = project_to_pixel(vp, DVec3::new(0.0, 0.5, 0.0), 200, 100);
        assert!(py < 50.0, "py = {py}");
        // Directly above the target: horizontally centred (f32 rounding only, 1e-4 px).
        assert!((px - 100.0).abs() < 1e-4, "px = {px}");
    }

    #[test]
    fn default_camera_projects_sphere_top_to_hand_computed_row() {
        // The tangent point of the unit sphere seen from (0,0,4) is at elevation asin(1/4);
        // y_ndc = tan(asin(0.25)) = 0.25/sqrt(1-1/16) = 0.2581989; py = H/2·(1 - y_ndc/tan 20°)
        // = 50·(1 - 0.2581989/0.3639702) = 14.530 for H = 100. Direction to the tangent point:
        // (0, sin, -cos) of that elevation; project a point along it.
        let camera = Camera::default();
        let elevation = (0.25f64).asin();
        let point = camera.eye + 3.0 * DVec3::new(0.0, elevation.sin(), -elevation.cos());
        let (_, py, _) = project_to_pixel(camera.view_projection(100, 100, 1.0), point, 100, 100);
        // 1e-3 px: f32 rounding (~1e-5 px) plus the 5-digit hand constant.
        assert!((py - 14.530).abs() < 1e-3, "py = {py}");
    }

    #[test]
    fn centre_ray_points_at_target() {
        // Tolerance 1e-12 rad: only f64 rounding of a few operations.
        let camera = oblique_camera();
        let ray = camera.primary_ray(320.0, 180.0, 640, 360);
        let expected = (camera.target - camera.eye).normalize();
        assert!(ray.angle_between(expected) < 1e-12);
    }

    #[test]
    fn row_zero_is_the_top() {
        let camera = Camera::default();
        let ray = camera.primary_ray(50.0, 0.5, 100, 100);
        assert!(ray.y > 0.0, "ray at py = 0.5 should point up, got {ray}");
        let ray = camera.primary_ray(0.5, 50.0, 100, 100);
        assert!(
            ray.x < 0.0,
            "ray at px = 0.5 should point left (-X), got {ray}"
        );
    }

    #[test]
    fn primary_ray_matches_hand_computed_corner() {
        // Default camera, 200×100, pixel (0, 0) centre: x_ndc = (2·0.5/200 - 1)·tan20°·2
        // = -0.995·0.36397023·2 = -0.72430076, y_ndc = (1 - 1/100)·0.36397023 = 0.36033053;
        // direction ∝ (x_ndc, y_ndc, -1) because the default camera frame is the world frame.
        let ray = Camera::default().primary_ray(0.5, 0.5, 200, 100);
        let expected = DVec3::new(-0.72430076, 0.36033053, -1.0).normalize();
        // 1e-7 rad: the hand constants have 8 significant digits.
        assert!(ray.angle_between(expected) < 1e-7, "{ray}");
    }

    #[test]
    fn depth_is_zero_at_near_and_one_at_far() {
        let camera = Camera::default();
        let projection = camera.projection_vulkan(1.0, 2.0, 10.0);
        let at = |z: f64| {
            let clip = projection * DVec4::new(0.0, 0.0, z, 1.0);
            clip.z / clip.w
        };
        // Exact in f64 up to a few ulps.
        assert!(at(-2.0).abs() < 1e-12);
        assert!((at(-10.0) - 1.0).abs() < 1e-12);
    }

    /// Every vertex of the bowl projects inside its box's screen bounds (with a pixel to spare
    /// for the rasteriser's sample positions), from several viewpoints; a box reaching behind the
    /// eye gives the whole image.
    #[test]
    fn screen_bounds_contain_every_projected_vertex() {
        let bowl = crate::raster::BuiltinMesh::Bowl.mesh();
        let bounds = bowl.bounding_box().unwrap();
        let (w, h) = (320, 200);
        for eye in [
            DVec3::new(1.3, 2.1, 3.7),
            DVec3::new(0.0, 0.2, 2.0),
            DVec3::new(-3.0, 1.0, 0.5),
        ] {
            let camera = Camera {
                eye,
                ..oblique_camera()
            };
            let r = camera.screen_bounds(bounds, w, h, bowl.bounding_radius());
            assert!(!r.is_empty() && r.x1 <= w && r.y1 <= h, "{r:?}");
            assert!(
                r != PixelRect {
                    x0: 0,
                    y0: 0,
                    x1: w,
                    y1: h
                },
                "a bowl in view is not the whole image"
            );
            let vp = camera.view_projection(w, h, bowl.bounding_radius());
            for p in &bowl.positions {
                let point = DVec3::new(p[0].into(), p[1].into(), p[2].into());
                let (x, y, _) = project_to_pixel(vp, point, w, h);
                // A pixel to spare inside every side the image edge does not clamp.
                let within = |v: f64, lo: u32, hi: u32, limit: u32| {
                    (lo == 0 || v >= f64::from(lo) + 1.0)
                        && (hi == limit || v <= f64::from(hi) - 1.0)
                };
                assert!(
                    within(x, r.x0, r.x1, w) && within(y, r.y0, r.y1, h),
                    "vertex at pixel ({x}, {y}) outside {r:?}"
                );
            }
        }
        let inside = Camera {
            eye: DVec3::new(0.0, 0.3, 0.0),
            ..oblique_camera()
        };
        assert_eq!(
            inside.screen_bounds(bounds, w, h, 1.0),
            PixelRect {
                x0: 0,
                y0: 0,
                x1: w,
                y1: h
            }
        );
    }

    #[test]
    fn depth_range_follows_a_scene_far_from_the_origin() {
        // The same view 1e5 from the origin: the range about the scene's own centre, not the
        // origin (which put near at ~2,800 and the scene, 3 to 5 away, in front of it).
        let offset = DVec3::new(1e5, 0.0, 1e5);
        let far_away = Camera {
            eye: Camera::default().eye + offset,
            target: Camera::default().target + offset,
            ..Camera::default()
        };
        let boxes = [(offset - DVec3::ONE, offset + DVec3::ONE)];
        let sphere = SceneSphere::around_boxes(boxes).unwrap();
        assert_eq!(sphere.center, offset);
        let (near, far) = far_away.depth_range(sphere);
        let radius = 3f64.sqrt();
        assert!(near <= 4.0 - radius && near > 0.0, "near {near}");
        assert!(far >= 4.0 + radius && far < 6.0, "far {far}");
        assert_eq!(SceneSphere::around_boxes([]), None);
    }

    #[test]
    fn depth_range_encloses_the_scene() {
        let (near, far) = Camera::default().depth_range(1.0);
        // Eye at distance 4, radius 1: the scene spans 3..5 along any ray through the centre.
        assert!(near < 3.0 && near > 2.9, "near {near}");
        assert!(far > 5.0 && far < 5.1, "far {far}");
        let inside = Camera {
            eye: DVec3::new(0.0, 0.0, 0.5),
            ..Camera::default()
        };
        let (near, far) = inside.depth_range(1.0);
        assert!(near > 0.0 && far > 1.5 && far / near <= 1.0001e4);
    }

    #[test]
    fn validate_rejects_each_bad_field() {
        assert!(Camera::default().validate().is_ok());
        let bad = [
            Camera {
                eye: DVec3::new(f64::NAN, 0.0, 4.0),
                ..Camera::default()
            },
            Camera {
                target: DVec3::new(0.0, 0.0, 4.0),
                ..Camera::default()
            },
            Camera {
                up: DVec3::new(0.0, 0.0, -2.0),
                ..Camera::default()
            },
            Camera {
                up: DVec3::ZERO,
                ..Camera::default()
            },
            Camera {
                fov_deg: 0.0,
                ..Camera::default()
            },
            Camera {
                fov_deg: 180.0,
                ..Camera::default()
            },
        ];
        let fields = [
            "camera.eye",
            "camera.target",
            "camera.up",
            "camera.up",
            "camera.fov_deg",
            "camera.fov_deg",
        ];
        for (camera, field) in bad.iter().zip(fields) {
            match camera.validate() {
                Err(Error::InvalidParameter { field: f, .. }) => assert_eq!(f, field),
                other => panic!("{camera:?}: expected invalid {field}, got {other:?}"),
            }
        }
    }
}
