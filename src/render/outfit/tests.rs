use super::regions::{garment_fields, FIELD_COLUMNS};
use super::*;
use crate::body::{joint, BodyModel, BodyParams};
use crate::math::Vec3;

fn model() -> BodyModel {
    BodyModel::load(crate::paths::crate_root().join("assets/body/SMPLX_NEUTRAL.npz")).unwrap()
}

fn column(slot: &str) -> usize {
    SLOTS.iter().position(|s| *s == slot).unwrap()
}

/// A plan that always draws the given styles.
fn only(top: TopStyle, bottom: BottomStyle, hair: HairStyle) -> OutfitPlan {
    let one = |k: usize, n: usize| (0..n).map(|i| f64::from(u8::from(i == k))).collect();
    OutfitPlan {
        tops: Shares::new(one(top as usize, TopStyle::ALL.len())),
        bottoms: Shares::new(one(bottom as usize, BottomStyle::ALL.len())),
        hair: Shares::new(one(hair as usize, HairStyle::ALL.len())),
        shoes: 1.0,
        ..OutfitPlan::default()
    }
}

#[test]
fn draws_are_the_seed_s_and_follow_the_shares() {
    let plan = OutfitPlan::default();
    assert_eq!(plan.draw(3), plan.draw(3));
    assert_ne!(plan.draw(3), plan.draw(4));
    let off = OutfitPlan {
        mode: OutfitsMode::Off,
        ..OutfitPlan::default()
    };
    assert_eq!(off.draw(0), None);
    let dresses = only(TopStyle::LongSleeves, BottomStyle::Dress, HairStyle::None);
    for i in 0..50 {
        let o = dresses.draw(i).unwrap();
        let top = o.garments.iter().find(|g| g.slot == "top").unwrap();
        let bottom = o.garments.iter().find(|g| g.slot == "bottom").unwrap();
        assert_eq!(
            (top.style.as_str(), bottom.style.as_str()),
            ("dress", "dress")
        );
        assert_eq!((top.fabric, top.base_rgb), (bottom.fabric, bottom.base_rgb));
        assert!(o.garments.iter().all(|g| g.slot != "hair"));
        assert!(o.garments.iter().any(|g| g.slot == "shoes"));
        assert!(o.cut.sleeve > 0.85, "{:?}", o.cut);
    }
    let mut seen = [0usize; 5];
    for i in 0..1000 {
        let o = plan.draw(i).unwrap();
        let style = &o
            .garments
            .iter()
            .find(|g| g.slot == "bottom")
            .unwrap()
            .style;
        seen[BottomStyle::ALL
            .iter()
            .position(|s| s.name() == style.as_str())
            .unwrap()] += 1;
        for g in &o.garments {
            assert!(
                g.base_rgb
                    .iter()
                    .chain(&g.accent_rgb)
                    .all(|c| (0.0..=1.0).contains(c)),
                "{g:?}"
            );
        }
    }
    // Shares 1.5 : 1 : 4 : 1 : 1 of 1000 (±5σ).
    let expected = [176.5, 117.6, 470.6, 117.6, 117.6];
    for (n, e) in seen.iter().zip(expected) {
        assert!(
            (*n as f64 - e).abs() < 5.0 * (e * (1.0 - e / 1000.0)).sqrt(),
            "{seen:?}"
        );
    }
}

#[test]
fn shares_tables_name_what_is_wrong() {
    let table = |pairs: &[(&str, f64)]| {
        pairs
            .iter()
            .map(|(k, v)| (k.to_string(), *v))
            .collect::<BTreeMap<_, _>>()
    };
    assert!(Shares::<TopStyle>::from_table(&table(&[("tunic", 1.0)]))
        .unwrap_err()
        .contains("unknown style `tunic`"));
    assert!(
        Shares::<TopStyle>::from_table(&table(&[("sleeveless", -1.0)]))
            .unwrap_err()
            .contains("`sleeveless`")
    );
    assert!(Shares::<HairStyle>::from_table(&table(&[("bob", 0.0)])).is_err());
    let s = Shares::<HairStyle>::from_table(&table(&[("bob", 2.0)])).unwrap();
    assert_eq!(s.weights, vec![0.0, 0.0, 0.0, 2.0, 0.0]);
}

/// The rest body's vertex nearest `p`.
fn nearest(v: &[Vec3], p: Vec3) -> usize {
    (0..v.len())
        .min_by(|&a, &b| (v[a] - p).length().total_cmp(&(v[b] - p).length()))
        .unwrap()
}

#[test]
fn garments_cover_what_they_should_on_the_rest_body() {
    let m = model();
    let shaped = m.shape(&[], &[]).unwrap();
    let (v, j) = (&shaped.v_shaped, shaped.rest_joints);
    let outfit = only(
        TopStyle::LongSleeves,
        BottomStyle::Trousers,
        HairStyle::Short,
    )
    .draw(0)
    .unwrap();
    let f = garment_fields(&m, &[], &outfit).unwrap();
    let on = |slot: &str, p: Vec3| f[nearest(v, p)][column(slot)] > 0.0;
    let mid = |a: usize, b: usize| 0.5 * (j[a] + j[b]);
    // The chest, the upper arm and the forearm in the top; the hand and the face not.
    let chest = nearest(v, j[joint::PELVIS] + Vec3::new(0.0, 0.35, 0.2));
    assert!(f[chest][column("top")] > 0.0);
    assert!(on(
        "top",
        mid(joint::LEFT_SHOULDER, joint::LEFT_ELBOW) + Vec3::new(0.0, 0.1, 0.0)
    ));
    assert!(on(
        "top",
        mid(joint::RIGHT_ELBOW, joint::RIGHT_WRIST) + Vec3::new(0.0, -0.1, 0.0)
    ));
    let hand = j[joint::LEFT_WRIST] + Vec3::new(0.08, 0.0, 0.0);
    assert!(!on("top", hand));
    let nose = v
        .iter()
        .copied()
        .filter(|p| p.y > 1.4)
        .max_by(|a, b| a.z.total_cmp(&b.z))
        .unwrap();
    for slot in ["top", "bottom", "hair", "shoes"] {
        assert!(!on(slot, nose), "{slot} on the nose");
    }
    // Trousers on the thigh and shin, not the torso's top; shoes on the soles; hair on
    // the crown and the back of the head.
    assert!(on("bottom", mid(joint::LEFT_HIP, joint::LEFT_KNEE)));
    assert!(on("bottom", mid(joint::RIGHT_KNEE, joint::RIGHT_ANKLE)));
    assert!(!on("bottom", chest_point(&j)));
    let sole = v
        .iter()
        .copied()
        .min_by(|a, b| a.y.total_cmp(&b.y))
        .unwrap();
    assert!(on("shoes", sole));
    assert!(!on("shoes", mid(joint::LEFT_KNEE, joint::LEFT_ANKLE)));
    let crown = v
        .iter()
        .copied()
        .max_by(|a, b| a.y.total_cmp(&b.y))
        .unwrap();
    assert!(on("hair", crown));
    assert!(on("hair", j[joint::HEAD] + Vec3::new(0.0, 0.05, -0.2)));
    assert!(!on("hair", chest_point(&j)));
    // Every row: the distances within [−1, 1] and the rest position last.
    for (row, p) in f.iter().zip(v) {
        assert!(row[..SLOTS.len()].iter().all(|d| (-1.0..=1.0).contains(d)));
        assert_eq!(
            row[SLOTS.len()..FIELD_COLUMNS],
            [p.x as f32, p.y as f32, p.z as f32]
        );
    }
}

fn chest_point(j: &[Vec3]) -> Vec3 {
    j[joint::PELVIS] + Vec3::new(0.0, 0.35, 0.2)
}

/// Where a garment's edge crosses the mesh's edges: the two vertices and the share of the way
/// from the first to the second.
fn crossings(
    faces: &[[u32; 3]],
    f: &[[f32; FIELD_COLUMNS]],
    col: usize,
) -> Vec<(usize, usize, f64)> {
    let mut out = Vec::new();
    for t in faces {
        for k in 0..3 {
            let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
            let (fa, fb) = (f[a][col] as f64, f[b][col] as f64);
            if a < b && (fa > 0.0) != (fb > 0.0) {
                out.push((a, b, fa / (fa - fb)));
            }
        }
    }
    out
}

/// A sleeve's end stays on the arm, at its share of the arm's length, for shapes at ±3σ and an
/// elbow bent to its limit or straight: every point where the sleeve's edge crosses a mesh edge
/// (on the posed body, as the renderer interpolates it) lies within 3 cm of the cut's distance
/// along the posed arm.
#[test]
fn a_sleeve_s_end_stays_on_the_arm_at_extreme_shapes_and_elbows() {
    let m = model();
    let plan = only(TopStyle::ShortSleeves, BottomStyle::Shorts, HairStyle::None);
    let mut worst: f64 = 0.0;
    for (shape, betas) in [
        ("mean", vec![]),
        ("+3σ", vec![3.0, 3.0, 3.0]),
        ("−3σ", vec![-3.0, -3.0, -3.0]),
        ("mixed", vec![3.0, -3.0, 3.0, -3.0]),
    ] {
        for seed in 0..3 {
            let outfit = plan.draw(seed).unwrap();
            let shaped = m.shape(&betas, &[]).unwrap();
            let f = garment_fields(&m, &betas, &outfit).unwrap();
            let edges = crossings(&m.faces, &f, column("top"));
            for elbow in [0.0, 2.4, -2.4] {
                let mut params = BodyParams {
                    betas: betas.clone(),
                    ..Default::default()
                };
                // The left elbow bent forward to its limit (about 140°), the right likewise.
                params.set_joint_axis_angle(joint::LEFT_ELBOW, Vec3::new(0.0, elbow, 0.0));
                params.set_joint_axis_angle(joint::RIGHT_ELBOW, Vec3::new(0.0, -elbow, 0.0));
                let posed = m.pose(&params).unwrap();
                for side in [0, 1] {
                    let [s, e, w] = if side == 0 {
                        [joint::LEFT_SHOULDER, joint::LEFT_ELBOW, joint::LEFT_WRIST]
                    } else {
                        [16 + 1, 18 + 1, 20 + 1]
                    };
                    let (js, je, jw) = (posed.joints[s], posed.joints[e], posed.joints[w]);
                    let upper = (je - js).length();
                    let target = outfit.cut.sleeve * (upper + (jw - je).length());
                    let mut n = 0;
                    for &(a, b, t) in &edges {
                        // The sleeve's edge: crossings on this side beyond the rest shoulder
                        // (the hem and neckline lie inside it).
                        let rest = shaped.v_shaped[a].lerp(shaped.v_shaped[b], t);
                        let shoulder = shaped.rest_joints[s];
                        if (rest.x - shoulder.x) * shoulder.x.signum() < 0.03
                            || (rest.y - shoulder.y).abs() > 0.15
                        {
                            continue;
                        }
                        let p = posed.vertices[a].lerp(posed.vertices[b], t);
                        let along_upper = (p - js).dot((je - js).normalize());
                        let along = if along_upper <= upper {
                            along_upper
                        } else {
                            upper + (p - je).dot((jw - je).normalize())
                        };
                        let miss = (along - target).abs();
                        worst = worst.max(miss);
                        assert!(
                            miss < 0.03,
                            "{shape}, seed {seed}, elbow {elbow}: a sleeve edge {along:.3} m along the arm, cut at {target:.3}"
                        );
                        // On the arm: within 8 cm of the bone it lies along.
                        let bone = if along_upper <= upper {
                            (js, je)
                        } else {
                            (je, jw)
                        };
                        let d = bone.1 - bone.0;
                        let q =
                            bone.0 + d * ((p - bone.0).dot(d) / d.length_squared()).clamp(0.0, 1.0);
                        assert!(
                            (p - q).length() < 0.08,
                            "{shape}: a sleeve edge {:.3} m off the arm",
                            (p - q).length()
                        );
                        n += 1;
                    }
                    assert!(
                        n >= 8,
                        "{shape}, seed {seed}: {n} sleeve edge crossings on side {side}"
                    );
                }
            }
        }
    }
    eprintln!("largest sleeve-end miss along the arm: {worst:.4} m");
}
