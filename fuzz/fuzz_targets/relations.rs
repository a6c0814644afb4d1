//! Relations text: an error value or relations with finite stamps and poses.
#![no_main]
use libfuzzer_sys::fuzz_target;
use odocal::io::relations::parse_relations;
use odocal_fuzz::check_pose;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(rels) = parse_relations(text, "fuzz.relations") {
        assert!(!rels.is_empty());
        for r in &rels {
            assert!(r.t1.is_finite() && r.t2.is_finite());
            check_pose("relation", &r.delta);
        }
    }
});
