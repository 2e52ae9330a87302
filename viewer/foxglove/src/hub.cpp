// SPDX-License-Identifier: Apache-2.0
#include "hub.hpp"

#include <algorithm>

#include "sim/foxglove/protocol.hpp"

namespace sim::foxglove {

void Hub::join(const std::shared_ptr<Client>& client) {
  std::lock_guard lock(mutex_);
  std::erase_if(clients_, [](const std::weak_ptr<Client>& w) { return w.expired(); });
  clients_.push_back(client);
  std::vector<Channel> channels;
  for (const auto& [id, stream] : channels_) channels.push_back(stream.channel);
  // The protocol asks for at least one advertise, even an empty one.
  client->send_text(advertise_json(channels));
}

void Hub::leave(const Client* client) {
  std::lock_guard lock(mutex_);
  std::erase_if(clients_, [&](const std::weak_ptr<Client>& w) {
    const auto c = w.lock();
    return !c || c.get() == client;
  });
  for (auto& [id, pump] : pumps_) pump->remove(client);
}

bool Hub::subscribe(const std::shared_ptr<Client>& client, std::uint32_t channel_id) {
  std::lock_guard lock(mutex_);
  const auto channel = channels_.find(channel_id);
  if (channel == channels_.end()) return false;
  if (channel->second.latched) {
    client->offer(channel->second.latched);  // what a late subscriber must still get
    return true;
  }
  auto& pump = pumps_[channel_id];
  if (!pump) {
    pump = std::make_shared<Pump>(channel->second.stream, channel_id, channel->second.layout,
                                  pump_options_);
    place(pump);
  }
  pump->add(client);
  return true;
}

void Hub::place(const std::shared_ptr<Pump>& pump) {
  for (const auto& runner : runners_) {
    if (runner->add(pump)) return;
  }
  runners_.push_back(std::make_unique<PumpRunner>());
  (void)runners_.back()->add(pump);
}

void Hub::retire(const Pump* pump) {
  for (const auto& runner : runners_) runner->remove(pump);
}

void Hub::unsubscribe(const Client* client, std::uint32_t channel_id) {
  std::lock_guard lock(mutex_);
  if (const auto it = pumps_.find(channel_id); it != pumps_.end()) it->second->remove(client);
}

void Hub::reap() {
  std::vector<std::unique_ptr<PumpRunner>> finished;
  std::lock_guard lock(mutex_);
  for (auto it = pumps_.begin(); it != pumps_.end();) {
    if (it->second->subscriber_count() == 0) {
      retire(it->second.get());
      it = pumps_.erase(it);
    } else {
      ++it;
    }
  }
  for (auto& runner : runners_) {
    if (runner->size() == 0) finished.push_back(std::move(runner));
  }
  std::erase(runners_, nullptr);
  // `finished` is declared before the lock: the runners join their threads after it is released.
}

void Hub::update(const CatalogChanges& changes) {
  const auto& added = changes.added;
  const auto& removed = changes.removed;
  std::lock_guard lock(mutex_);
  std::vector<std::shared_ptr<Client>> clients;
  for (const auto& w : clients_) {
    if (auto c = w.lock()) clients.push_back(std::move(c));
  }
  if (!removed.empty()) {
    for (const std::uint32_t id : removed) {
      channels_.erase(id);
      if (auto it = pumps_.find(id); it != pumps_.end()) {
        retire(it->second.get());
        pumps_.erase(it);
      }
    }
    const std::string text = unadvertise_json(removed);
    for (const auto& c : clients) {
      for (const std::uint32_t id : removed) c->drop_channel(id);
      c->send_text(text);
    }
  }
  if (!added.empty()) {
    std::vector<Channel> channels;
    for (const auto& stream : added) {
      channels_[stream.channel.id] = stream;
      channels.push_back(stream.channel);
    }
    const std::string text = advertise_json(channels);
    for (const auto& c : clients) c->send_text(text);
  }
  // Clients that do not subscribe to the channel ignore the offer.
  for (const auto& message : changes.updated) {
    if (auto it = channels_.find(message->channel_id); it != channels_.end()) {
      it->second.latched = message;
    }
    for (const auto& c : clients) c->offer(message);
  }
}

void Hub::stop() {
  std::map<std::uint32_t, std::shared_ptr<Pump>> pumps;
  std::vector<std::unique_ptr<PumpRunner>> runners;
  {
    std::lock_guard lock(mutex_);
    pumps.swap(pumps_);
    runners.swap(runners_);
  }
  runners.clear();  // joins their threads; then no pump is in use
}

std::size_t Hub::pump_count() const {
  std::lock_guard lock(mutex_);
  return pumps_.size();
}

}  // namespace sim::foxglove
