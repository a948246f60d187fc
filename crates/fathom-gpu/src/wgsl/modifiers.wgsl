// Distance modifiers (fathom-core modifiers.rs): `fn mod_<Name>(d: f32, k: f32, <params>) -> f32`.

fn mod_Round(d: f32, k: f32, radius: f32) -> f32 {
    return d - radius * k;
}

fn mod_Onion(d: f32, k: f32, thickness: f32) -> f32 {
    return abs(d) - thickness * k;
}
