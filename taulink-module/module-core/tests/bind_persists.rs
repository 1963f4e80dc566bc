//! A bind on the host, end to end: the long press reaches the link, the bind result is
//! saved through the settings store onto the fault-injecting mock flash, and a "rebooted"
//! module core built from what the flash holds shows the bound state.

use embassy_futures::block_on;
use module_core::app::{Action, App};
use module_core::button::ButtonEvent;
use module_core::channels::ChannelFrame;
use module_core::ports::{HandsetOutput, LinkPort, LinkStats};
use module_core::settings::{Settings, SettingsStore};
use module_core::status::LinkState;
use sequential_storage::mock_flash::{MockFlashBase, WriteCountCheck};

type Flash = MockFlashBase<8, 4, 1024>;

#[derive(Default)]
struct Link {
    binds: u32,
    stats: LinkStats,
}

impl LinkPort for Link {
    fn send_channels(&mut self, _channels: &ChannelFrame) {}
    fn set_input_timeout_ms(&mut self, _timeout_ms: u16) {}
    fn can_send_record(&self) -> bool {
        false
    }
    fn send_record(&mut self, _record: &[u8]) {}
    fn stats(&self) -> LinkStats {
        self.stats
    }
    fn start_bind(&mut self) {
        self.binds += 1;
    }
}

struct Handset;

impl HandsetOutput for Handset {
    fn on_telemetry(&mut self, _record: &[u8]) {}
    fn on_link_stats(&mut self, _stats: &LinkStats) {}
}

#[test]
fn bind_id_survives_a_reboot() {
    block_on(async {
        let range = 0..8 * 4096;
        let mut store = SettingsStore::new(
            Flash::new(WriteCountCheck::Twice, None, true),
            range.clone(),
        )
        .unwrap();
        let settings = store.load().await.unwrap().unwrap_or_default();
        let mut app = App::new(settings, Link::default(), Handset, false).unwrap();
        assert_eq!(
            app.on_radio_present(true),
            Some(Action::Led(LinkState::Unbound))
        );
        app.on_button(ButtonEvent::LongPress);
        assert_eq!(app.link().binds, 1);
        let Action::Save(bound) = app.on_bind_complete(0xC0FF_EE01) else {
            panic!("a bind must be saved");
        };
        store.save(&bound).await.unwrap();

        // Reboot: a new store over the same flash, a new core from what it holds.
        let mut store = SettingsStore::new(store.release(), range).unwrap();
        let loaded = store.load().await.unwrap().unwrap();
        assert_eq!(loaded.bind_id, 0xC0FF_EE01);
        assert_eq!(
            loaded,
            Settings {
                bind_id: 0xC0FF_EE01,
                ..Settings::default()
            }
        );
        let mut app = App::new(loaded, Link::default(), Handset, false).unwrap();
        assert_eq!(
            app.on_radio_present(true),
            Some(Action::Led(LinkState::Searching))
        );
    });
}
