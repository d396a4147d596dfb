// The interface of the Roller comes from its modelDescription.xml alone:
// the shared generator checks it and emits the tables `src/description.rs` includes.
fn main() {
    fmi_build::generate("modelDescription.xml", "model_description.rs");
}
