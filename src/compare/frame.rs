//! What `compare` makes of the frame before it measures: the light it measures, and the notes its report
//! carries about the scene.

use shadow_core::FrameInputs;
use shadow_core::material::AlphaMode;

/// The notes of a report on `frame` ([`super::CompareReport::notes`]).
#[must_use]
pub fn scene_notes(frame: &FrameInputs) -> Vec<String> {
    let mut blended: Vec<&str> = Vec::new();
    for inst in frame.instances.iter().filter(|i| i.casts_shadow && i.material.alpha_mode == AlphaMode::Blend) {
        if !blended.contains(&inst.material.name.as_str()) {
            blended.push(&inst.material.name);
        }
    }
    let mut notes = Vec::new();
    if !blended.is_empty() {
        notes.push(format!(
            "blended casters cast as opaque ones, in every technique and in the reference alike (materials: {})",
            blended.join(", ")
        ));
    }
    notes
}

/// `frame` with the light whose reach covers the most of a `width x height` view (of equals, the first)
/// moved first, and that light's index, where it is not light 0 (a light with a range may light little or
/// nothing of the view): `compare`'s figures are the first light's, and a light that reaches few pixels
/// would measure little. `None` where light 0 is that light.
#[must_use]
pub fn widest_first(frame: &FrameInputs, width: u32, height: u32) -> Option<(FrameInputs, usize)> {
    let area = |k: usize| frame.reach(&frame.lights[k], width, height).rect.area();
    let k = (0..frame.lights.len()).rev().max_by_key(|&k| area(k))?;
    if k == 0 {
        return None;
    }
    let mut moved = frame.clone();
    let light = moved.lights.remove(k);
    moved.lights.insert(0, light);
    // A light past the list of shadows casts as the default says.
    if k < moved.shadows.len() {
        let shadow = moved.shadows.remove(k);
        moved.shadows.insert(0, shadow);
    } else if !moved.shadows.is_empty() {
        moved.shadows.insert(0, Default::default());
    }
    Some((moved, k))
}

/// The report's note on a light moved first ([`widest_first`]).
pub(super) fn measured_note(k: usize) -> String {
    format!(
        "the figures are of light {k}, the light whose reach covers the most of the view (light 0's covers less), \
         moved first for the comparison"
    )
}

#[cfg(test)]
mod tests {
    use super::{scene_notes, widest_first};
    use shadow_core::FrameInputs;
    use shadow_core::material::AlphaMode;
    use shadow_core::scenes::{self, SceneParams};

    /// A report on a scene with blended casters says they cast as opaque ones, naming their materials;
    /// one with none says nothing.
    #[test]
    fn blended_casters_are_noted() {
        let mut scene = scenes::build("cutout", &SceneParams::default()).expect("cutout");
        let notes = |scene: &shadow_core::Scene| scene_notes(&FrameInputs::from_first_camera(scene).expect("frame"));
        assert!(notes(&scene).is_empty());
        let card = scene.materials().find(|(_, m)| m.name == "checkerboard").expect("the card").0;
        scene.material_mut(card).expect("material").alpha_mode = AlphaMode::Blend;
        let notes = notes(&scene);
        assert_eq!(notes.len(), 1);
        assert!(notes[0].contains("cast as opaque") && notes[0].contains("checkerboard"), "{}", notes[0]);
    }

    #[test]
    fn the_light_that_reaches_the_most_of_the_view_is_measured() {
        let frame = |name: &str| {
            FrameInputs::from_first_camera(&scenes::build(name, &SceneParams::default()).expect("scene"))
                .expect("frame")
        };
        assert!(widest_first(&frame("cubes"), 64, 48).is_none(), "a light without a range reaches everywhere");
        let yard = frame("yard");
        let (moved, k) = widest_first(&yard, 200, 150).expect("yard's light 0 is out of view");
        let area = |k: usize| yard.reach(&yard.lights[k], 200, 150).rect.area();
        assert!(k > 0 && area(0) == 0 && (0..yard.lights.len()).all(|j| area(j) <= area(k)));
        assert_eq!(moved.lights[0].kind, yard.lights[k].kind);
        assert_eq!(moved.lights.len(), yard.lights.len());
        assert!(!moved.reach(&moved.lights[0], 200, 150).is_empty());
        assert_eq!(&moved.lights[1..=k], &yard.lights[..k], "the lights before it follow it");
    }
}
