//! Effect SPECs: an error value or an effect with finite parameters whose
//! printed SPEC parses back to the same effect.
#![no_main]
use libfuzzer_sys::fuzz_target;
use odocal::effects::Effect;

fuzz_target!(|data: &[u8]| {
    let Ok(spec) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(e) = Effect::parse(spec) {
        assert!(e.params().iter().all(|(_, v)| v.is_finite()), "{e:?}");
        let printed = e.to_string();
        assert_eq!(Effect::parse(&printed).as_ref(), Ok(&e), "{printed}");
    }
});
