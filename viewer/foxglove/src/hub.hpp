// SPDX-License-Identifier: Apache-2.0
// The server's shared state between the catalog, the clients and the pumps: which channels are
// advertised, which clients are connected, and one pump per channel that anyone subscribes to,
// fed by as few runner threads as the WaitSet's limit allows (one per 128 subscribed channels).
// It knows clients only through the Client interface, so it has no socket code.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "catalog.hpp"
#include "pump.hpp"

namespace sim::foxglove {

class Client : public Subscriber {
 public:
  // Queues a text message (advertise, unadvertise, status) in order; called from any thread.
  virtual void send_text(std::string text) = 0;
  // The channel went away; its subscription ends (the client has been sent unadvertise).
  virtual void drop_channel(std::uint32_t channel_id) = 0;
};

class Hub {
 public:
  explicit Hub(PumpOptions pump_options) : pump_options_(pump_options) {}
  Hub(const Hub&) = delete;
  Hub& operator=(const Hub&) = delete;

  // A new client: it is sent the current channels, in order with every later change.
  void join(const std::shared_ptr<Client>& client);
  // The client is gone: its subscriptions end.
  void leave(const Client* client);

  // Starts the channel's messages flowing to the client (a latched channel's current message at
  // once); false when the channel is not advertised.
  bool subscribe(const std::shared_ptr<Client>& client, std::uint32_t channel_id);
  void unsubscribe(const Client* client, std::uint32_t channel_id);

  // Ends the pumps nobody subscribes to any more, and the runners left without pumps. Called
  // from the catalog's thread, not from a client's: a runner stops only after the frame it is
  // encoding, and a flood of subscribe/unsubscribe then reuses the running pump.
  void reap();

  // From the catalog.
  // A latched channel's new message goes to every client subscribed to it.
  void update(const CatalogChanges& changes);

  // Ends every pump (before the clients' executor goes away).
  void stop();

  std::size_t pump_count() const;

 private:
  // Hands the pump to a runner with room, starting one if none has.
  void place(const std::shared_ptr<Pump>& pump);
  void retire(const Pump* pump);

  const PumpOptions pump_options_;
  mutable std::mutex mutex_;
  std::map<std::uint32_t, AdvertisedStream> channels_;
  std::vector<std::weak_ptr<Client>> clients_;
  std::map<std::uint32_t, std::shared_ptr<Pump>> pumps_;
  std::vector<std::unique_ptr<PumpRunner>> runners_;
};

}  // namespace sim::foxglove
