use glam::DVec3;
use shikki::model::*;
fn main() {
    let n = DVec3::new(-0.7158667057151841, 0.09814578620888444, 0.6913047550089108);
    let v = DVec3::new(
        -0.7185780736810701,
        -0.08762800691766262,
        -0.689903532697464,
    );
    let l = DVec3::new(-0.9465810442044882, 0.20043703995766304, 0.2526050667855876);
    let h = (v + l).normalize();
    println!(
        "nv {} nl {} nh {} vh {} |v+l| {}",
        n.dot(v),
        n.dot(l),
        n.dot(h),
        v.dot(h),
        (v + l).length()
    );
    let m = LacquerMaterial::preset("smooth").unwrap();
    let p = m.brdf_params().unwrap();
    let f = m.fresnel_table().unwrap();
    println!(
        "{:?} diff {:?}",
        lacquer_brdf(&p, &f, n, v, l),
        brdf::view_dependent_diffuse(&p, n.dot(v))
    );
}
