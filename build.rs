// The interface of ConvertingSpan comes from modelDescription.xml alone:
// the shared generator checks it and emits the tables `src/description.rs` includes.
fn main() {
    fmi_build::generate("modelDescription.xml", "model_description.rs");
}
