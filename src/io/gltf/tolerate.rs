//! Valid glTF the `gltf` crate's strict types refuse, made readable before they see it.
//!
//! The Khronos glTF-Validator's own sample files include valid files the crate cannot
//! deserialise or validates too strictly: scenes without a `nodes` array, animation channels
//! without a `node` (`KHR_animation_pointer`), lights of a type a later extension may define.
//! myriad renders the static pose, so animations are dropped here (counted, for the warning);
//! a scene without nodes gets an empty list; a light of an unknown type becomes a placeholder
//! the loader skips with a warning; an accessor of a type glTF does not define (which the
//! validator lets pass where nothing reads it) becomes a placeholder that is an error where it
//! is read; an integer written as a float (`1.0`, which JSON does not
//! tell apart from `1`) becomes that integer.

use std::collections::{BTreeMap, BTreeSet};

use serde_json::Value;

/// What was changed, for the loader's warnings.
#[derive(Default)]
pub struct Tolerated {
    /// Animations dropped.
    pub animations: usize,
    /// Indices of `KHR_lights_punctual` lights of an unknown type (now placeholders).
    pub unknown_lights: BTreeSet<usize>,
    /// Accessors of a `type` glTF does not define, with it (now SCALAR placeholders, an
    /// error where something reads them).
    pub unknown_accessors: BTreeMap<usize, String>,
}

/// The accessor types glTF defines.
const ACCESSOR_TYPES: [&str; 7] = ["SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT3", "MAT4"];

/// Every integral number in `v` written as a float, as an integer (the crate's index and
/// count fields refuse `1.0`; its float fields take integers).
fn integers(v: &mut Value) {
    match v {
        Value::Number(n) if n.is_f64() => {
            let x = n.as_f64().unwrap_or(f64::NAN);
            if x.fract() == 0.0 && x.abs() < 9.0e15 {
                *v = if x < 0.0 { Value::from(x as i64) } else { Value::from(x as u64) };
            }
        }
        Value::Array(a) => a.iter_mut().for_each(integers),
        Value::Object(o) => o.values_mut().for_each(integers),
        _ => {}
    }
}

/// The light types `KHR_lights_punctual` defines.
const LIGHT_TYPES: [&str; 3] = ["directional", "point", "spot"];

/// Changes `root` (a glTF document's JSON) as the module docs say.
pub fn tolerate(root: &mut Value) -> Tolerated {
    let mut t = Tolerated::default();
    integers(root);
    if let Some(obj) = root.as_object_mut() {
        t.animations = obj.remove("animations").and_then(|a| a.as_array().map(Vec::len)).unwrap_or(0);
    }
    if let Some(scenes) = root.get_mut("scenes").and_then(Value::as_array_mut) {
        for scene in scenes.iter_mut().filter_map(Value::as_object_mut) {
            scene.entry("nodes").or_insert_with(|| Value::Array(Vec::new()));
        }
    }
    let accessors = root.get_mut("accessors").and_then(Value::as_array_mut);
    for (i, accessor) in accessors.into_iter().flatten().enumerate() {
        let ty = accessor.get("type").and_then(Value::as_str).unwrap_or("").to_string();
        if !ACCESSOR_TYPES.contains(&ty.as_str())
            && let Some(obj) = accessor.as_object_mut()
        {
            t.unknown_accessors.insert(i, ty);
            obj.insert("type".into(), Value::from("SCALAR"));
        }
    }
    let lights = root.pointer_mut("/extensions/KHR_lights_punctual/lights").and_then(Value::as_array_mut);
    for (i, light) in lights.into_iter().flatten().enumerate() {
        let known = light.get("type").and_then(Value::as_str).is_some_and(|ty| LIGHT_TYPES.contains(&ty));
        if !known && let Some(obj) = light.as_object_mut() {
            obj.insert("type".into(), Value::from("point"));
            t.unknown_lights.insert(i);
        }
    }
    t
}
